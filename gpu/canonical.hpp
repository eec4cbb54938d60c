// The finite triangles of a GPU triangulation in core's canonical order (core/canonical.hpp), sorted on the GPU:
// bucketed by their smallest vertex (a counting sort), each bucket sorted by the second vertex, one download. A
// vertex with a huge fan (over CANONICAL_BUCKET_MAX triangles of its own) sends the whole sort to the 64-bit radix
// sort of one key per slot instead. Replaces a host sort that took 0.3-0.7 s for 1M-2M points.
#pragma once
#include <vector>

#include "core/model.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/triangulation.hpp"

namespace cdtgpu::gpu {

class TriangleSorter {
 public:
  TriangleSorter(const Context& ctx, const Primitives& prims);
  // Finite triangles, each starting at its smallest vertex, counter-clockwise, sorted. `gpu_ms`: device time of
  // the key pass and the sort (timestamps), if given.
  // Overwrites tri.nbrs with the sorted triangles and tri.vertex_slots (if any) with bucket sizes: both are not
  // needed any more, so no extra buffers.
  // `out`: storage to reuse (its pages already touched, say), resized to the finite triangles.
  Triangles download(GpuTriangulation& tri, double* gpu_ms = nullptr,
                                 Triangles out = {}) const;
  // The same left on the device: the count of finite triangles, sorted at the start of tri.nbrs.
  uint32_t sort(GpuTriangulation& tri, double* gpu_ms = nullptr) const;

  BufferCache* cache = nullptr;  // where the keys live between calls (shared keys); null: a cache of its own

 private:
  const Context& ctx_;
  const Primitives& prims_;
  Pass count_, place_, bucket_, keys_, write_;
  mutable BufferCache scratch_;  // kept between calls, grown to the largest triangulation so far
};

}  // namespace cdtgpu::gpu
