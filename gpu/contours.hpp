// Contour lines of a TIN with marching triangles on the GPU, chained on the CPU: core/contours.hpp's lines,
// byte for byte once written.
//
//   gpu::GpuContourer contourer(ctx, prims);
//   gpu::DeviceTin tin = gpu::upload_tin(ctx, mesh);                // gpu/tin.hpp
//   std::vector<Contour> lines = contourer.lines(tin, mesh, 10.0);  // == contour_lines(mesh, 10.0)
//
// Two stages, the count/scan/write layout: contour_count gives each triangle its levels (first, count: lowest
// z < level <= highest z, by binary search over the levels' doubles), a scan gives offsets, contour_write
// writes each triangle's segments (triangle order, then level) into one compact list, with core's crossing
// formula (`precise`, division correctly rounded). Triangles go in chunks whose segments fit one storage
// buffer. The host sorts the segments by level (a counting sort, triangle order kept) and chains each level
// with core's chain_contours, levels in parallel. Cost on the host: O(segments), the chaining's hash maps.
#pragma once
#include <cstdint>
#include <vector>

#include "core/contours.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/tin.hpp"

namespace cdtgpu::gpu {

class GpuContourer {
 public:
  GpuContourer(const Context& ctx, const Primitives& prims);
  // `mesh` is the one `tin` was uploaded from (the host side needs its triangles for the edge keys).
  // max_chunk_segments: segments per chunk at most (0: what one buffer holds); tests make it small.
  std::vector<Contour> lines(const DeviceTin& tin, const Mesh& mesh, double interval,
                             uint64_t max_levels = 100000, uint64_t max_chunk_segments = 0) const;
  // Milliseconds of the last call: on the device (timestamps), and the host's sorting and chaining.
  mutable double gpu_ms = 0, chain_ms = 0;

 private:
  const Context& ctx_;
  const Primitives& prims_;
  Pass count_, write_;
};

}  // namespace cdtgpu::gpu
