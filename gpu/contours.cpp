// Chunks, buffers and dispatches of the GPU contours, then the host's sort by level and chaining.
#include "gpu/contours.hpp"

#include <algorithm>
#include <chrono>
#include <execution>
#include <numeric>
#include <string>

#include "gpu/check.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

static_assert(sizeof(SegmentRecord) == 48, "SegmentRecord: 4 uint, 4 double");

GpuContourer::GpuContourer(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      count_(create_pass(ctx, {"contour_count", 5, sizeof(ContourPush)})),
      write_(create_pass(ctx, {"contour_write", 7, sizeof(ContourPush)})) {}

std::vector<Contour> GpuContourer::lines(const DeviceTin& tin, const Mesh& mesh, double interval,
                                         uint64_t max_levels, uint64_t max_chunk_segments) const {
  gpu_ms = chain_ms = 0;
  const ContourLevels lv = contour_levels(mesh, interval, max_levels);
  if (lv.count == 0) return {};
  if (lv.count > UINT32_MAX) throw DeviceError("contours: more than 2^32 levels");
  std::vector<double> levels(lv.count);
  for (size_t i = 0; i < lv.count; ++i) levels[i] = lv.level(i);
  Buffer level_buf = upload_new(ctx_, levels, "contour levels");

  const uint32_t nt = tin.num_triangles;
  uint64_t seg_cap = ctx_.info.max_storage_buffer_range / sizeof(SegmentRecord);
  if (max_chunk_segments) seg_cap = std::min(seg_cap, max_chunk_segments);
  // A triangle gives at most one segment per level: a chunk of 2^32 / levels triangles cannot overflow the
  // 32-bit scan.
  uint32_t chunk = uint32_t(std::max<uint64_t>(1, std::min<uint64_t>(nt, UINT32_MAX / lv.count)));
  Buffer first = create_buffer(ctx_, uint64_t(chunk) * 4, "contour first level");
  Buffer counts = create_buffer(ctx_, uint64_t(chunk) * 4, "contour counts");
  Buffer offsets = create_buffer(ctx_, uint64_t(chunk) * 4, "contour offsets");
  Buffer segs;
  std::vector<std::vector<cdtgpu::ContourSegment>> per(lv.count);
  std::vector<cdtgpu::ContourSegment>* per_level = per.data();
  std::vector<SegmentRecord> host;

  for (uint32_t t0 = 0; t0 < nt;) {
    const uint32_t n = std::min(chunk, nt - t0);
    const ContourPush push{t0, n, uint32_t(lv.count)};
    const uint64_t groups = (uint64_t(n) + CONTOUR_WG - 1) / CONTOUR_WG;
    Profiler prof(ctx_, 2);
    {
      Recorder rec(ctx_);
      prof.begin(rec, "count");
      rec.dispatch_groups(count_, {level_buf, tin.xyz, tin.tris, first, counts}, push, groups);
      prims_.exclusive_scan(rec, counts, offsets, n);
      prof.end(rec);
      rec.submit();
    }
    const uint64_t total = prims_.scanned_total(offsets, counts, n);
    if (total > seg_cap) {
      if (n == 1) throw DeviceError("contours: one triangle's segments do not fit one device buffer");
      chunk = std::max<uint32_t>(1, n / 2);  // this chunk again, smaller
      continue;
    }
    if (total) {
      if (segs.size < total * sizeof(SegmentRecord))
        segs = create_buffer(ctx_, total * sizeof(SegmentRecord), "contour segments");
      Recorder rec(ctx_);
      prof.begin(rec, "write");
      rec.dispatch_groups(write_, {level_buf, tin.xyz, tin.tris, first, counts, offsets, segs}, push, groups);
      prof.end(rec);
      rec.submit();
    }
    for (const StageTime& s : prof.results()) gpu_ms += s.ms;
    const auto h0 = std::chrono::steady_clock::now();
    host.resize(total);
    if (total) download(ctx_, segs, host.data(), total * sizeof(SegmentRecord));
    for (const SegmentRecord& s : host) {
      const Triangle& tri = mesh.triangles[s.tri];
      const uint32_t from = s.edges & 3u, to = (s.edges >> 2) & 3u;
      const double level = levels[s.level];
      per_level[s.level].push_back({contour_edge_key(tri[from], tri[(from + 1) % 3]),
                                    contour_edge_key(tri[to], tri[(to + 1) % 3]),
                                    {s.px, s.py, level},
                                    {s.qx, s.qy, level}});
    }
    chain_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - h0).count();
    t0 += n;
  }

  const auto h0 = std::chrono::steady_clock::now();
  std::vector<size_t> ks(lv.count);
  std::iota(ks.begin(), ks.end(), size_t(0));
  std::vector<std::vector<Contour>> lines(lv.count);
  std::transform(std::execution::par, ks.begin(), ks.end(), lines.begin(),
                 [&](size_t k) { return chain_contours(levels[k], per[k]); });
  std::vector<Contour> all;
  for (auto& v : lines)
    for (Contour& c : v) all.push_back(std::move(c));
  chain_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - h0).count();
  return all;
}

}  // namespace cdtgpu::gpu
