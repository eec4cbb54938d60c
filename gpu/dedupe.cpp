#include "gpu/dedupe.hpp"

#include "shaders/layout_dedupe.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

uint64_t groups(uint32_t n) { return (uint64_t(n) + DEDUPE_WG - 1) / DEDUPE_WG; }

}  // namespace

PointDeduper::PointDeduper(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      keys_(create_pass(ctx, {"dedupe_keys", 3, sizeof(DedupeKeysPush)})),
      flags_(create_pass(ctx, {"dedupe_flags", 3, sizeof(DedupePush)})),
      scatter_(create_pass(ctx, {"dedupe_scatter", 8, sizeof(DedupePush)})) {}

DedupedPoints PointDeduper::run(const Buffer& xy, uint32_t n) const {
  DedupedPoints out;
  out.map = create_buffer(ctx_, uint64_t(n) * sizeof(uint32_t), "dedupe map");
  if (n == 0) {
    out.xy = create_buffer(ctx_, 0, "vertices");
    out.first = create_buffer(ctx_, 0, "dedupe first");
    return out;
  }
  Buffer unique = create_buffer(ctx_, uint64_t(n) * 2 * sizeof(double), "vertices");
  Buffer first = create_buffer(ctx_, uint64_t(n) * sizeof(uint32_t), "dedupe first");
  Buffer count = create_buffer(ctx_, sizeof(uint32_t), "dedupe count");
  Recorder rec(ctx_);
  const Buffer& keys = rec.temp(uint64_t(n) * sizeof(uint64_t), "dedupe keys");
  const Buffer& idx = rec.temp(uint64_t(n) * sizeof(uint32_t), "dedupe index");
  const Buffer& flags = rec.temp(uint64_t(n) * sizeof(uint32_t), "dedupe flags");
  const Buffer& offsets = rec.temp(uint64_t(n) * sizeof(uint32_t), "dedupe offsets");
  // LSD order: sort by y, then stably by x, so the result is by (x, y) with ties in input order.
  rec.dispatch_groups(keys_, {xy, keys, idx}, DedupeKeysPush{n, 1, 0}, groups(n));
  prims_.radix_sort(rec, keys, idx, n, 64);
  rec.dispatch_groups(keys_, {xy, keys, idx}, DedupeKeysPush{n, 0, 1}, groups(n));
  prims_.radix_sort(rec, keys, idx, n, 64);
  rec.dispatch_groups(flags_, {xy, idx, flags}, DedupePush{n}, groups(n));
  prims_.exclusive_scan(rec, flags, offsets, n);
  rec.dispatch_groups(scatter_, {xy, idx, flags, offsets, unique, out.map, first, count}, DedupePush{n},
                      groups(n));
  rec.submit();
  download(ctx_, count, &out.count, sizeof(uint32_t));
  out.xy = std::move(unique);
  out.first = std::move(first);
  return out;
}

DedupedHost dedupe_points(const Context& ctx, std::span<const double> xy) {
  Primitives prims(ctx);
  PointDeduper deduper(ctx, prims);
  const uint32_t n = uint32_t(xy.size() / 2);
  Buffer input = upload_new(ctx, xy, "points");
  DedupedPoints d = deduper.run(input, n);
  DedupedHost h;
  h.xy = download_vector<double>(ctx, d.xy, size_t(d.count) * 2);
  h.map = download_vector<uint32_t>(ctx, d.map, n);
  h.first = download_vector<uint32_t>(ctx, d.first, d.count);
  return h;
}

PointMerge merge_points(const PointDeduper& deduper, std::span<const double> xy) {
  const Context& ctx = deduper.context();
  const uint32_t n = uint32_t(xy.size() / 2);
  Buffer input = upload_new(ctx, xy.subspan(0, size_t(n) * 2), "points");
  DedupedPoints d = deduper.run(input, n);
  PointMerge m;
  m.vertex_of = download_raw<uint32_t>(ctx, d.map, n);
  m.first = download_raw<uint32_t>(ctx, d.first, d.count);
  return m;
}

}  // namespace cdtgpu::gpu
