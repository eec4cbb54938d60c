// Bands, buffers and dispatches of the GPU rasteriser; the shaders (raster_*.comp) hold the rules.
#include "gpu/raster.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <string>

#include "core/touched.hpp"
#include "gpu/check.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

GpuRasteriser::GpuRasteriser(const Context& ctx, const Primitives& prims)
    : ctx_(ctx),
      prims_(prims),
      spans_(create_pass(ctx, {"raster_spans", 5, sizeof(RasterPush)})),
      claim_(create_pass(ctx, {"raster_claim", 8, sizeof(RasterPush)})),
      exact_(create_pass(ctx, {"raster_exact", 7, sizeof(RasterPush)})),
      values_(create_pass(ctx, {"raster_values", 5, sizeof(RasterPush)})) {}

Raster GpuRasteriser::rasterise(const DeviceTin& tin, const GridSpec& g, uint64_t max_band_cells) const {
  gpu_ms = 0;
  Raster r;
  r.spec = g;
  if (g.ncols == 0 || g.nrows == 0) return r;
  resize_touched(r.z, g.ncols * g.nrows);  // 800 MB at 10^8 cells: zeroed on all cores, on huge pages
  const uint64_t range = ctx_.info.max_storage_buffer_range;
  uint64_t band_cells = std::min<uint64_t>(range / sizeof(double), uint64_t(1) << 31);
  if (max_band_cells) band_cells = std::min(band_cells, max_band_cells);
  if (g.ncols > band_cells || g.ncols > UINT32_MAX)
    throw DeviceError("a grid row of " + std::to_string(g.ncols) +
                      " cells is more than one device buffer holds (" + std::to_string(band_cells) +
                      " cells)");
  // The scan of (triangle, row) items is 32-bit: a band of at most 2^32 / triangles rows cannot overflow it.
  const uint64_t nt64 = std::max<uint64_t>(tin.num_triangles, 1);
  const uint64_t band_rows =
      std::max<uint64_t>(1, std::min({band_cells / g.ncols, uint64_t(g.nrows), uint64_t(UINT32_MAX) / nt64}));

  // The grid's numbers as doubles: k of the first column and of the top row are integers below 2^53.
  const double params[RASTER_PARAMS] = {g.cell, double(g.ix0), double(g.iy0 + int64_t(g.nrows) - 1),
                                        Raster::nodata};
  Buffer grid = create_buffer(ctx_, sizeof(params), "raster params");
  upload(ctx_, grid, params, sizeof(params));
  const uint32_t nt = tin.num_triangles;
  Buffer spans = create_buffer(ctx_, uint64_t(nt) * 16, "raster spans");
  Buffer counts = create_buffer(ctx_, uint64_t(nt) * 4, "raster counts");
  Buffer offsets = create_buffer(ctx_, uint64_t(nt) * 4, "raster offsets");
  Buffer owner = create_buffer(ctx_, band_rows * g.ncols * 4, "raster owner");
  Buffer z = create_buffer(ctx_, band_rows * g.ncols * 8, "raster z");
  // Centres the filters cannot decide, for raster_exact; grown when a band needs more.
  uint32_t queue_cap = uint32_t(std::min<uint64_t>(band_rows * g.ncols, uint64_t(1) << 20));
  Buffer queue = create_buffer(ctx_, uint64_t(queue_cap) * 16, "raster exact queue");
  Buffer queue_count = create_buffer(ctx_, 4, "raster exact queue count");
  auto claim = [&](Recorder& rec, const RasterPush& push) {
    rec.dispatch_groups(claim_, {grid, tin.xyz, tin.tris, spans, offsets, owner, queue, queue_count}, push,
                        (uint64_t(push.items) + RASTER_WG - 1) / RASTER_WG);
  };
  const uint64_t tri_groups = (uint64_t(nt) + RASTER_WG - 1) / RASTER_WG;

  for (uint64_t row0 = 0; row0 < g.nrows; row0 += band_rows) {
    const uint64_t rows = std::min(band_rows, g.nrows - row0);
    RasterPush push{nt, uint32_t(g.ncols), uint32_t(row0), uint32_t(rows), 0, 0};
    Profiler prof(ctx_, 3);
    uint32_t items = 0;
    if (nt) {
      Recorder rec(ctx_);
      prof.begin(rec, "spans");
      rec.dispatch_groups(spans_, {grid, tin.xyz, tin.tris, spans, counts}, push, tri_groups);
      prims_.exclusive_scan(rec, counts, offsets, nt);
      prof.end(rec);
      rec.submit();
      const uint64_t total = prims_.scanned_total(offsets, counts, nt);
      if (total > UINT32_MAX) throw DeviceError("raster: more than 2^32 (triangle, row) items in one band");
      items = uint32_t(total);
    }
    push.items = items;
    push.queue_cap = queue_cap;
    {
      Recorder rec(ctx_);
      prof.begin(rec, "claim");
      rec.fill(owner, RASTER_NO_TRI);
      rec.fill(queue_count, 0);
      if (items) claim(rec, push);
      prof.end(rec);
      rec.submit();
    }
    uint32_t queued = 0;
    download(ctx_, queue_count, &queued, 4);
    if (queued >
        queue_cap) {  // the queue was too short: again with one that holds them (atomicMin is idempotent)
      queue_cap = queued;
      queue = create_buffer(ctx_, uint64_t(queue_cap) * 16, "raster exact queue");
      push.queue_cap = queue_cap;
      Recorder rec(ctx_);
      rec.fill(queue_count, 0);
      claim(rec, push);
      rec.submit();
    }
    Recorder rec(ctx_);
    prof.begin(rec, "exact and values");
    if (queued)
      rec.dispatch_groups(exact_, {grid, tin.xyz, tin.tris, spans, queue, queue_count, owner}, push,
                          (uint64_t(queued) + RASTER_WG - 1) / RASTER_WG);
    rec.dispatch_groups(values_, {grid, tin.xyz, tin.tris, owner, z}, push,
                        (rows * g.ncols + RASTER_WG - 1) / RASTER_WG);
    prof.end(rec);
    rec.submit();
    for (const StageTime& s : prof.results()) {
      gpu_ms += s.ms;
      spdlog::debug("gpu raster band at row {}: {} {:.2f} ms ({} centres decided exactly)", row0, s.name,
                    s.ms, queued);
    }
    download(ctx_, z, r.z.data() + row0 * g.ncols, rows * g.ncols * 8);
  }
  return r;
}

}  // namespace cdtgpu::gpu
