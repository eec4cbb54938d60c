// A tile's final triangles found on the device, next to the neighbours (core/tiles.hpp, TileFinalizer): a flag
// per slot from the circumdisk test, then the final region's border from the neighbours, and every other slot
// unlisted, so that the canonical sort (gpu/canonical) then downloads the final triangles only. Replaces the
// host's test and border, which took 1.5 s per 64M-point tile on 16 threads.
#pragma once
#include <vector>

#include "core/model.hpp"
#include "core/tiles.hpp"
#include "gpu/buffers.hpp"
#include "gpu/passes.hpp"
#include "gpu/triangulation.hpp"

namespace cdtgpu::gpu {

class TileFinalPasses {
 public:
  explicit TileFinalPasses(const Context& ctx);
  // The border edges (vertex ids of the triangulation, final triangle on the left) in the order the device's
  // threads appended them: the caller sorts them once the device is free (GpuCdt::unstage_triangles). Leaves in `tri`
  // only the final triangles for the sort: its other slots lose their first vertex. `gpu_ms`: device time.
  std::vector<Edge> mark(GpuTriangulation& tri, const TileRect& rect, BufferCache& cache, double* gpu_ms) const;

 private:
  const Context& ctx_;
  Pass final_, border_;
};

}  // namespace cdtgpu::gpu
