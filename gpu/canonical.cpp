#include "gpu/canonical.hpp"

#include <spdlog/spdlog.h>

#include <bit>
#include <chrono>

#include "core/touched.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

TriangleSorter::TriangleSorter(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      keys_(create_pass(ctx, {"canonical_keys", 4, sizeof(CanonicalKeysPush)})),
      write_(create_pass(ctx, {"canonical_write", 4, sizeof(CanonicalKeysPush)})) {}

std::vector<Triangle> TriangleSorter::download(GpuTriangulation& tri, double* gpu_ms) const {
  std::vector<Triangle> out;
  if (gpu_ms) *gpu_ms = 0;
  const uint32_t slots = tri.num_slots;
  if (slots == 0) return out;
  BufferCache& buffers = cache ? *cache : scratch_;
  const Buffer& keys = buffers.get(ctx_, kSlots8[0], uint64_t(slots) * 8, "canonical keys");
  const Buffer& payload = buffers.get(ctx_, kSlots4[0], uint64_t(slots) * 4, "canonical payload");
  const Buffer& count = buffers.get(ctx_, "canonical count", 4);
  const Buffer& keys2 = buffers.get(ctx_, kSlots8[1], uint64_t(slots) * 8, "canonical keys 2");
  const Buffer& payload2 = buffers.get(ctx_, kSlots4[1], uint64_t(slots) * 4, "canonical payload 2");
  const Buffer& tris = tri.nbrs;  // no longer needed: it takes the sorted triples
  const uint64_t groups = (uint64_t(slots) + CANONICAL_WG - 1) / CANONICAL_WG;
  {
    Recorder rec(ctx_);
    Profiler prof(ctx_, 1);
    prof.begin(rec, "canonical order");
    rec.fill(count, 0);
    // Two vertex fields of `shift` bits: the digits above them are zero and need no pass.
    const CanonicalKeysPush push{slots, tri.num_points, uint32_t(std::bit_width(tri.num_points))};
    rec.dispatch_groups(keys_, {tri.verts, keys, payload, count}, push, groups);
    prims_.radix_sort(rec, keys, payload, slots, 64, 2 * push.shift, {&keys2, &payload2});
    rec.dispatch_groups(write_, {keys, payload, tris, count}, push, groups);
    prof.end(rec);
    rec.submit();
    if (gpu_ms) *gpu_ms = prof.results().front().ms;
  }
  uint32_t finite = 0;
  gpu::download(ctx_, count, &finite, 4);
  static_assert(sizeof(Triangle) == 12, "Triangle is three packed uint32");
  const auto t0 = std::chrono::steady_clock::now();
  resize_touched(out, finite);
  const auto t1 = std::chrono::steady_clock::now();
  gpu::download(ctx_, tris, out.data(), uint64_t(finite) * sizeof(Triangle));
  spdlog::debug("canonical download: {:.1f} ms to allocate, {:.1f} ms to copy {} triangles",
                std::chrono::duration<double, std::milli>(t1 - t0).count(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count(), finite);
  return out;
}

}  // namespace cdtgpu::gpu
