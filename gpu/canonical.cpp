#include "gpu/canonical.hpp"

#include <spdlog/spdlog.h>

#include <bit>
#include <chrono>
#include <functional>

#include "core/touched.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

TriangleSorter::TriangleSorter(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      count_(create_pass(ctx, {"canonical_count", 4, sizeof(CanonicalKeysPush)})),
      place_(create_pass(ctx, {"canonical_place", 4, sizeof(CanonicalKeysPush)})),
      bucket_(create_pass(ctx, {"canonical_bucket", 4, sizeof(CanonicalKeysPush)})),
      keys_(create_pass(ctx, {"canonical_keys", 4, sizeof(CanonicalKeysPush)})),
      write_(create_pass(ctx, {"canonical_write", 4, sizeof(CanonicalKeysPush)})) {}

uint32_t TriangleSorter::sort(GpuTriangulation& tri, double* gpu_ms) const {
  if (gpu_ms) *gpu_ms = 0;
  const uint32_t slots = tri.num_slots;
  if (slots == 0) return 0;
  BufferCache& buffers = cache ? *cache : scratch_;
  const uint32_t n = tri.num_points;
  const Buffer& count = buffers.get(ctx_, "canonical count", 8);  // finite triangles, a bucket too large
  const Buffer& tris = tri.nbrs;  // no longer needed: it takes the sorted triples
  const uint64_t groups = (uint64_t(slots) + CANONICAL_WG - 1) / CANONICAL_WG;
  // Two vertex fields of `shift` bits in the radix keys: the digits above them are zero and need no pass.
  const CanonicalKeysPush push{slots, n, uint32_t(std::bit_width(n))};
  // Buckets by smallest vertex (count, scan, place, sort each bucket by its second vertex): a few light passes
  // instead of six radix passes over 64-bit keys.
  // Records one way of sorting between the count's reset and the timestamps; returns its device time.
  auto sort_on_gpu = [&](const std::function<void(Recorder&)>& record) {
    Recorder rec(ctx_);
    Profiler prof(ctx_, 1);
    prof.begin(rec, "canonical order");
    rec.fill(count, 0);
    record(rec);
    prof.end(rec);
    rec.submit();
    return prof.results().front().ms;
  };
  uint32_t counts[2] = {0, 0};
  {
    // The vertex slots are not needed any more either: they hold the bucket sizes when the build left them.
    const Buffer& bucket = tri.vertex_slots.buffer ? tri.vertex_slots
                                                   : buffers.get(ctx_, kPoints4[0], uint64_t(n) * 4, "canonical buckets");
    const Buffer& offsets = buffers.get(ctx_, kPoints4[1], uint64_t(n) * 4, "canonical offsets");
    const Buffer& rank = buffers.get(ctx_, kSlots4[0], uint64_t(slots) * 4, "canonical ranks");
    const double ms = sort_on_gpu([&](Recorder& rec) {
      rec.fill(bucket, 0);
      rec.dispatch_groups(count_, {tri.verts, bucket, rank, count}, push, groups);
      prims_.exclusive_scan(rec, bucket, offsets, n);
      rec.dispatch_groups(place_, {tri.verts, offsets, rank, tris}, push, groups);
      rec.dispatch_groups(bucket_, {bucket, offsets, tris, count}, push,
                          (uint64_t(n) + CANONICAL_WG - 1) / CANONICAL_WG);
    });
    if (gpu_ms) *gpu_ms = ms;
    gpu::download(ctx_, count, counts, 8);
  }
  if (counts[1]) {  // a bucket too large for one invocation (a vertex with a huge fan): the radix sort
    const Buffer& keys = buffers.get(ctx_, kSlots8[0], uint64_t(slots) * 8, "canonical keys");
    const Buffer& payload = buffers.get(ctx_, kSlots4[0], uint64_t(slots) * 4, "canonical payload");
    const Buffer& keys2 = buffers.get(ctx_, kSlots8[1], uint64_t(slots) * 8, "canonical keys 2");
    const Buffer& payload2 = buffers.get(ctx_, kSlots4[1], uint64_t(slots) * 4, "canonical payload 2");
    const double ms = sort_on_gpu([&](Recorder& rec) {
      rec.dispatch_groups(keys_, {tri.verts, keys, payload, count}, push, groups);
      prims_.radix_sort(rec, keys, payload, slots, 64, 2 * push.shift, {&keys2, &payload2});
      rec.dispatch_groups(write_, {keys, payload, tris, count}, push, groups);
    });
    if (gpu_ms) *gpu_ms += ms;
  }
  return counts[0];
}

Triangles TriangleSorter::download(GpuTriangulation& tri, double* gpu_ms, Triangles out) const {
  const uint32_t finite = sort(tri, gpu_ms);
  static_assert(sizeof(Triangle) == 12, "Triangle is three packed uint32");
  const auto t0 = std::chrono::steady_clock::now();
  resize_touched(out, finite);  // no work where `out` holds that many already
  const auto t1 = std::chrono::steady_clock::now();
  if (finite) gpu::download(ctx_, tri.nbrs, out.data(), uint64_t(finite) * sizeof(Triangle));
  spdlog::debug("canonical download: {:.1f} ms to allocate, {:.1f} ms to copy {} triangles",
                std::chrono::duration<double, std::milli>(t1 - t0).count(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count(), finite);
  return out;
}

}  // namespace cdtgpu::gpu
