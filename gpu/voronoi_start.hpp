// The Voronoi first stage (`--initial-dt voronoi`, issue 30; the paper's first step): the points discretised
// onto a grid, a digital Voronoi diagram by jump flooding (shaders/vd_*.comp), its dual triangles checked
// exactly on the host and repaired (gpu/voronoi_check) into a valid triangulation of the sites it kept. The
// Delaunay build (gpu/delaunay) then flips it Delaunay and inserts the points the grid lost; the result is the
// same unique triangulation as its default start's. The method and its costs: docs/gpu-delaunay.md.
//
//   VoronoiStarter vd(ctx);
//   VoronoiStats vs;
//   std::optional<VoronoiStart> s = vd.run(rec, points, n, true, vs);   // points: dvec2 in build numbering
//   if (!s) ...;    // no valid start after kMaxRepairs demotions: the caller starts the default way
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/recorder.hpp"
#include "gpu/voronoi_check.hpp"

namespace cdtgpu::gpu {

struct VoronoiStats {
  bool used = false;      // the build asked for the Voronoi start
  bool fallback = false;  // no valid start: the default start ran instead
  uint32_t grid_width = 0, grid_height = 0;
  uint32_t sites = 0;    // points the last flood started from (one per occupied cell, demoted ones not)
  uint32_t kept = 0;     // vertices of the start triangulation
  uint32_t lost = 0;     // points the rounds inserted (several in a cell, vanished regions, demoted sites)
  uint32_t repairs = 0;  // floods again after demoting sites
  uint32_t demoted = 0;
  uint32_t full_floods = 0;  // short floods that left cells empty, flooded again in full
  uint64_t flips = 0;        // flips that made the start Delaunay
  uint32_t flip_passes = 0;  // and their dispatched passes
  uint64_t device_bytes = 0;  // the stage's own buffers (grids, dual, per-point flags), on top of the build's
  // "vd discretise", "vd flood", "vd dual" (GPU timestamps, all floods summed), "vd repair (host)" (downloads,
  // exact checks, slot layout and upload, host clock); the builder adds "vd flips" (GPU).
  std::vector<std::pair<std::string, double>> stage_ms;
};

// The start: slots in build numbering and every point's loc code (shaders/layout_dt.h: a vertex, or a slot near
// the point to start its first walk from).
struct VoronoiStart {
  StartSlots slots;
  RawVector<uint32_t> loc;
  double corners[6] = {};  // a finite triangle of the start (the relocation's cone centre)
};

class VoronoiStarter {
 public:
  explicit VoronoiStarter(const Context& ctx);

  // `points`: n dvec2 (not all collinear). `timed`: GPU timestamps into stats.stage_ms.
  std::optional<VoronoiStart> run(Recorder& rec, const Buffer& points, uint32_t n, bool timed,
                                  VoronoiStats& stats) const;

  // Floods again after demoting the sites the checks blamed, at most this often.
  uint32_t max_repairs = 4;
  // Floods jump at most this far (then halve to 1, and 1 again); a repair's starts from the last grid with the
  // demoted sites' cells emptied. A flood that leaves cells empty (regions wider than ~2 short_jump cells) is
  // done again in full, from the seeds. 0: every flood from the seeds, with jumps from max(W, H) / 2.
  uint32_t short_jump = 16;
  // Grid cells per point (fewer for the largest inputs: the grid stays within kMaxCells).
  double cells_per_point = 4;

 private:
  const Context& ctx_;
  Pass seed_, clear_, flood_, dual_;
};

}  // namespace cdtgpu::gpu
