#include "gpu/canonical.hpp"

#include <bit>

#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

TriangleSorter::TriangleSorter(const Context& ctx, const Primitives& prims)
    : ctx_(ctx), prims_(prims), keys_(create_pass(ctx, {"canonical_keys", 4, sizeof(CanonicalKeysPush)})) {}

std::vector<Triangle> TriangleSorter::download(const GpuTriangulation& tri, double* gpu_ms) const {
  std::vector<Triangle> out;
  if (gpu_ms) *gpu_ms = 0;
  const uint32_t slots = tri.num_slots;
  if (slots == 0) return out;
  BufferCache& buffers = cache ? *cache : scratch_;
  const Buffer& keys = buffers.get(ctx_, kSlots8[0], uint64_t(slots) * 8, "canonical keys");
  const Buffer& payload = buffers.get(ctx_, kSlots4[0], uint64_t(slots) * 4, "canonical payload");
  const Buffer& count = buffers.get(ctx_, "canonical count", 4);
  {
    Recorder rec(ctx_);
    Profiler prof(ctx_, 1);
    prof.begin(rec, "canonical order");
    rec.fill(count, 0);
    rec.dispatch_groups(keys_, {tri.verts, keys, payload, count}, CanonicalKeysPush{slots, tri.num_points},
                        (uint64_t(slots) + CANONICAL_WG - 1) / CANONICAL_WG);
    // Keys stay below (num_points + 1) << 32: the digits above that are zero and need no pass.
    prims_.radix_sort(rec, keys, payload, slots, 64, 32 + std::bit_width(tri.num_points));
    prof.end(rec);
    rec.submit();
    if (gpu_ms) *gpu_ms = prof.results().front().ms;
  }
  uint32_t finite = 0;
  gpu::download(ctx_, count, &finite, 4);
  // Straight from the mapped staging memory into the result: no intermediate host vectors (page faults).
  out.resize(finite);
  download_with(ctx_, keys, uint64_t(finite) * 8, [&](const void* mapped) {
    const uint32_t* k = static_cast<const uint32_t*>(mapped);
    for (uint32_t i = 0; i < finite; ++i) out[i][0] = k[2 * i + 1], out[i][1] = k[2 * i];
  });
  download_with(ctx_, payload, uint64_t(finite) * 4, [&](const void* mapped) {
    const uint32_t* c = static_cast<const uint32_t*>(mapped);
    for (uint32_t i = 0; i < finite; ++i) out[i][2] = c[i];
  });
  return out;
}

}  // namespace cdtgpu::gpu
