// The Voronoi first stage's driver: grid, flood and dual on the GPU, the exact check on the host, demotions and
// floods again until the dual is valid or the repairs run out. What and why: docs/gpu-delaunay.md.
#include "gpu/voronoi_start.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <functional>

#include "core/timing.hpp"
#include "gpu/profiler.hpp"
#include "shaders/layout_dt.h"
#include "shaders/layout_vd.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

// 64 MiB per grid copy: lavapipe binds at most 128 MiB, and two copies flood.
constexpr uint64_t kMaxCells = uint64_t(1) << 24;
constexpr uint32_t kMaxSide = 1u << 15;
constexpr uint32_t kNone = UINT32_MAX;
constexpr uint32_t kGrain = 1 << 14;

uint64_t groups(uint64_t n) { return (n + VD_WG - 1) / VD_WG; }

void add_ms(std::vector<std::pair<std::string, double>>& stages, const std::string& name, double ms) {
  auto it = std::find_if(stages.begin(), stages.end(), [&](const auto& e) { return e.first == name; });
  if (it == stages.end())
    stages.push_back({name, ms});
  else
    it->second += ms;
}

// Square cells over the bounding box, about cells_per_point per point: with 4, a uniform input loses ~12% of
// its points to shared cells (1 - (1 - e^-1/4) * 4), and the grid costs 8 bytes per cell while it floods.
VdGridPush grid_for(std::span<const double> xy, uint32_t n, double cells_per_point) {
  using Box = std::array<double, 4>;  // x0, y0, x1, y1
  const Box box = tbb::parallel_reduce(
      tbb::blocked_range<uint32_t>(0, n, kGrain), Box{xy[0], xy[1], xy[0], xy[1]},
      [&](const tbb::blocked_range<uint32_t>& r, Box b) {
        for (uint32_t i = r.begin(); i < r.end(); ++i)
          b = {std::min(b[0], xy[2 * i]), std::min(b[1], xy[2 * i + 1]), std::max(b[2], xy[2 * i]),
               std::max(b[3], xy[2 * i + 1])};
        return b;
      },
      [](const Box& a, const Box& b) {
        return Box{std::min(a[0], b[0]), std::min(a[1], b[1]), std::max(a[2], b[2]), std::max(a[3], b[3])};
      });
  const double x0 = box[0], y0 = box[1], x1 = box[2], y1 = box[3];
  const double w = x1 - x0, h = y1 - y0;
  const double cells = std::min(double(kMaxCells), std::max(16.0, cells_per_point * n));
  double cell = std::sqrt(w * h / cells);
  cell = std::max({cell, w / kMaxSide, h / kMaxSide});
  if (!(cell > 0)) cell = std::max(w, h);  // a degenerate box (the caller excludes all-collinear inputs)
  VdGridPush g{};
  g.width = uint32_t(std::clamp(std::ceil(w / cell), 1.0, double(kMaxSide)));
  g.height = uint32_t(std::clamp(std::ceil(h / cell), 1.0, double(kMaxSide)));
  while (uint64_t(g.width) * g.height > kMaxCells) {  // rounding up both sides can overshoot
    cell *= 1.01;
    g.width = uint32_t(std::clamp(std::ceil(w / cell), 1.0, double(kMaxSide)));
    g.height = uint32_t(std::clamp(std::ceil(h / cell), 1.0, double(kMaxSide)));
  }
  g.x0 = x0;
  g.y0 = y0;
  g.cell = cell;
  return g;
}

}  // namespace

VoronoiStarter::VoronoiStarter(const Context& ctx)
    : ctx_(ctx),
      seed_(create_pass(ctx, {"vd_seed", 6, sizeof(VdGridPush)})),
      clear_(create_pass(ctx, {"vd_clear", 3, sizeof(VdGridPush)})),
      flood_(create_pass(ctx, {"vd_flood", 4, sizeof(VdGridPush)})),
      dual_(create_pass(ctx, {"vd_dual", 6, sizeof(VdGridPush)})) {}

// Discretise, flood, dual on the GPU; check on the host; on failure demote the blamed sites and go again.
std::optional<VoronoiStart> VoronoiStarter::run(Recorder& rec, const Buffer& points, uint32_t n, bool timed,
                                                VoronoiStats& stats) const {
  auto t0 = std::chrono::steady_clock::now();
  double host_ms = 0;
  const std::vector<double> xy = download_vector<double>(ctx_, points, size_t(n) * 2);
  VdGridPush grid = grid_for(xy, n, cells_per_point);
  stats.grid_width = grid.width;
  stats.grid_height = grid.height;
  const uint64_t cells = uint64_t(grid.width) * grid.height;
  // Distinct dual triangles number at most 2 per site; duplicates from neighbouring grid corners come on top.
  // Within the device's binding limit (lavapipe: 128 MiB, 11M triangles; above ~5M points on it the dual may
  // overflow, which gives up like any overflow).
  const uint32_t capacity =
      uint32_t(std::min<uint64_t>(3 * uint64_t(n) + 64, ctx_.props.limits.maxStorageBufferRange / 12));
  stats.device_bytes = uint64_t(n) * 24 + cells * 8 + uint64_t(capacity) * 12 + VD_COUNT_WORDS * 4;
  Buffer demoted = create_buffer(ctx_, uint64_t(n) * 4, "vd demoted");
  Buffer cell_of = create_buffer(ctx_, uint64_t(n) * 4, "vd cell of point");
  Buffer sites = create_buffer(ctx_, uint64_t(n) * 8, "vd site positions");
  Buffer blamed = create_buffer(ctx_, uint64_t(n) * 4, "vd blamed");
  Buffer blame_list = create_buffer(ctx_, uint64_t(n) * 4, "vd blame list");
  Buffer grids[2] = {create_buffer(ctx_, cells * 4, "vd grid a"), create_buffer(ctx_, cells * 4, "vd grid b")};
  Buffer tris = create_buffer(ctx_, uint64_t(capacity) * 12, "vd dual triangles");
  Buffer count = create_buffer(ctx_, VD_COUNT_WORDS * 4, "vd counts");
  std::vector<uint32_t> demoted_host(n, 0);
  std::optional<Profiler> prof;
  if (timed) prof.emplace(ctx_, 64);
  auto begin = [&](const char* name) {
    if (prof) prof->begin(rec, name);
  };
  auto end = [&] {
    if (prof) prof->end(rec);
  };
  std::optional<VoronoiStart> result;
  host_ms += ms_since(t0);
  const uint64_t tiles = uint64_t((grid.width + VD_TILE - 1) / VD_TILE) * ((grid.height + VD_TILE - 1) / VD_TILE);
  uint32_t cur = 0;  // the grid copy the last flood ended in
  // One flood and its dual, submitted; returns the counter words. A repair starts from the last flood's grid
  // with the demoted sites' cells emptied and reseeded. Jumps `top` .. 1, then 1 again (JFA+1: fixes most of
  // the plain flood's errors).
  const uint32_t full = std::bit_floor(std::max({grid.width, grid.height, 2u}) - 1);
  auto flood = [&](bool repair, uint32_t top) {
    begin("vd discretise");
    rec.fill(count, 0);
    rec.fill(blamed, 0);
    VdGridPush seed = grid;
    seed.n = n;
    seed.step = repair ? 1 : 0;
    if (repair) {
      rec.dispatch_groups(clear_, {demoted, grids[cur], grids[1 - cur]}, grid, groups(cells));
      cur = 1 - cur;
    } else {
      cur = 0;
      rec.fill(grids[0], VD_NONE);
    }
    rec.dispatch_groups(seed_, {points, demoted, grids[cur], cell_of, sites, grids[1 - cur]}, seed, groups(n));
    end();
    begin("vd flood");
    std::vector<uint32_t> steps;
    for (uint32_t s = top; s >= 1; s /= 2) steps.push_back(s);
    steps.push_back(1);
    for (size_t i = 0; i < steps.size(); ++i) {
      VdGridPush pass = grid;
      pass.step = steps[i];
      pass.n = i + 1 == steps.size();
      rec.dispatch_groups(flood_, {sites, grids[cur], grids[1 - cur], count}, pass, tiles);
      cur = 1 - cur;
    }
    end();
    begin("vd dual");
    VdGridPush dual = grid;
    dual.n = capacity;
    rec.dispatch_groups(dual_, {grids[cur], tris, count, points, blamed, blame_list}, dual, groups(cells));
    end();
    rec.submit();
    if (prof) {
      for (const StageTime& s : prof->results()) add_ms(stats.stage_ms, s.name, s.ms);
      prof->reset();
    }
    std::array<uint32_t, VD_COUNT_WORDS> counts;
    download(ctx_, count, counts.data(), sizeof(counts));
    return counts;
  };
  for (uint32_t attempt = 0; attempt <= max_repairs && !result; ++attempt) {
    t0 = std::chrono::steady_clock::now();
    if (attempt > 0) upload(ctx_, demoted, demoted_host.data(), uint64_t(n) * 4);
    host_ms += ms_since(t0);
    if (attempt == 0) rec.fill(demoted, 0);
    // Short jumps first (a dense seed grid, or a repair's holes, need no long ones); cells they leave empty
    // (sparse regions, wide holes) send the attempt to a full flood.
    const uint32_t top = short_jump ? std::min(full, std::bit_floor(short_jump)) : full;
    std::array<uint32_t, VD_COUNT_WORDS> counts = flood(attempt > 0 && short_jump > 0, top);
    if (top < full && counts[VD_COUNT_EMPTY] != 0) {
      ++stats.full_floods;
      counts = flood(false, full);
    }
    t0 = std::chrono::steady_clock::now();
    if (counts[VD_COUNT_OVERFLOW] != 0) {  // never seen; a start is an optimisation, so give up rather than grow
      host_ms += ms_since(t0);
      break;
    }
    std::vector<uint32_t> offenders;
    std::optional<StartSlots> slots;
    if (counts[VD_COUNT_BLAMED] != 0) {  // dual_to_slots would fail its first check, blaming these
      offenders.resize(counts[VD_COUNT_BLAMED]);
      download(ctx_, blame_list, offenders.data(), offenders.size() * 4);
      std::sort(offenders.begin(), offenders.end());
    } else {
      RawVector<Triangle> dual_tris(counts[VD_COUNT_TRIS]);  // not zeroed: the download writes it
      if (!dual_tris.empty()) download(ctx_, tris, dual_tris.data(), dual_tris.size() * 12);
      slots = dual_to_slots(xy, std::move(dual_tris), offenders, counts[VD_COUNT_UNDECIDED] == 0);
    }
    // The flooded grid: only for the start's loc codes and the last attempt's site count.
    RawVector<uint32_t> owner;
    if (slots || offenders.empty() || attempt == max_repairs) {
      owner.resize(cells);
      download(ctx_, grids[cur], owner.data(), cells * 4);
      std::vector<uint8_t> site(n, 0);
      tbb::parallel_for(tbb::blocked_range<uint64_t>(0, cells, kGrain), [&](const tbb::blocked_range<uint64_t>& r) {
        for (uint64_t c = r.begin(); c < r.end(); ++c)
          if (owner[c] != VD_NONE) std::atomic_ref<uint8_t>(site[owner[c]]).store(1, std::memory_order_relaxed);
      });
      stats.sites = tbb::parallel_reduce(
          tbb::blocked_range<uint32_t>(0, n, kGrain), 0u,
          [&](const tbb::blocked_range<uint32_t>& r, uint32_t sum) {
            for (uint32_t i = r.begin(); i < r.end(); ++i) sum += site[i];
            return sum;
          },
          std::plus<uint32_t>());
    }
    if (slots) {
      VoronoiStart v;
      // A vertex's loc names a slot it is a corner of; a lost point's, a slot at the site owning its cell (its
      // first walk is then short), else the first.
      const RawVector<uint32_t>& slot_of = slots->slot_of;
      RawVector<uint32_t> cell(n);
      download(ctx_, cell_of, cell.data(), uint64_t(n) * 4);
      v.loc.resize(n);
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, kGrain), [&](const tbb::blocked_range<uint32_t>& r) {
        for (uint32_t i = r.begin(); i < r.end(); ++i) {
          const uint32_t o = owner[cell[i]];
          v.loc[i] = slot_of[i] != kNone                    ? DT_INSERTED | NBR(slot_of[i], DT_INSIDE)
                     : o != VD_NONE && slot_of[o] != kNone ? NBR(slot_of[o], DT_INSIDE)
                                                            : NBR(0u, DT_INSIDE);
        }
      });
      for (uint32_t k = 0; k < 3; ++k) {
        v.corners[2 * k] = xy[2 * size_t(slots->verts[k])];
        v.corners[2 * k + 1] = xy[2 * size_t(slots->verts[k]) + 1];
      }
      stats.kept = slots->vertices;
      stats.lost = n - slots->vertices;
      v.slots = std::move(*slots);
      result = std::move(v);
    } else if (!offenders.empty() && attempt < max_repairs) {
      for (uint32_t o : offenders) stats.demoted += !demoted_host[o];
      for (uint32_t o : offenders) demoted_host[o] = 1;
      ++stats.repairs;
    } else {
      host_ms += ms_since(t0);
      break;
    }
    host_ms += ms_since(t0);
  }
  stats.fallback = !result;
  add_ms(stats.stage_ms, "vd repair (host)", host_ms);
  return result;
}

}  // namespace cdtgpu::gpu
