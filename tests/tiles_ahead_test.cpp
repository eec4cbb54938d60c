// Tiles begun before the resolve ends (core/tiles_ahead): on a clean input the tiles' mesh is the single run's
// and every tile call came after the resolve had cleared its x-range; on an input whose constraints cross, the
// early tiles are dropped and the resolved input's tiles give the single run's mesh. Also the resolve's
// progress on its own: its cleared x only grows, and ends at +inf exactly when nothing is split.
#include "core/tiles_ahead.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <cmath>
#include <future>
#include <limits>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/workloads.hpp"
#include "tests/tile_layouts.hpp"

namespace cdtgpu {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct AheadRun {
  std::optional<Triangles> ahead;
  ResolvedInput resolved;
  int calls = 0, too_early = 0;  // tile and merge calls; those made before the resolve cleared their x-range
};

AheadRun run_ahead(const PreparedInput& p, uint64_t tile_points) {
  AheadRun run;
  ResolveProgress progress;
  std::atomic<int> calls{0}, too_early{0};
  // The CGAL triangulator, checking that the resolve had cleared everything up to the call's largest x (its
  // vertices are sorted by x) before the call.
  const TileTriangulator checked = [&](const Points& v, const std::vector<Edge>& s, std::string_view what) {
    ++calls;
    if (!v.empty() && !progress.changes.load() && !(progress.clean_below.load() == kInf || v.back().x < progress.clean_below.load()))
      ++too_early;
    return cgal_tile_triangulator()(v, s, what);
  };
  auto resolving = std::async(std::launch::async, [&] { return resolve_if_needed(p, progress, 2); });
  TileOptions opt;
  opt.max_tile_points = tile_points;
  run.ahead = tiled_cdt_ahead(p, progress, opt, checked);
  run.resolved = resolving.get();
  run.calls = calls.load();
  run.too_early = too_early.load();
  return run;
}

TEST(TilesAhead, CleanInputGivesTheSingleRunsTrianglesWithoutWaitingForTheWholeResolve) {
  // Large enough for the resolve's sweep to go in several ranges (it reports each).
  InputSet in = uniform_points(200000, 7);
  add_dt_edge_constraints(in, 50000, 0.2, 3);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  for (uint64_t tp : {2000, 20000}) {
    const AheadRun run = run_ahead(p, tp);
    ASSERT_TRUE(run.ahead.has_value()) << "tiles of " << tp;
    EXPECT_TRUE(run.resolved.unchanged);
    EXPECT_TRUE(run.resolved.vertices.empty()) << "a clean input is not copied";
    EXPECT_EQ(single.mesh.vertices, p.vertices);
    EXPECT_TRUE(*run.ahead == single.mesh.triangles) << "tiles of " << tp;
    EXPECT_GT(run.calls, 2);
    EXPECT_EQ(run.too_early, 0) << "tiles of " << tp;
  }
}

// The tiles' side, with the progress driven by hand: cleared in nine steps over the input's x-range, 30 ms
// apart, then everywhere once a tile has been triangulated (or after 10 s: a tile that never begins before
// that is what this test catches). No tile may be triangulated before its x-range is cleared, and the mesh is
// the single run's.
TEST(TilesAhead, EachTileWaitsForItsXRange) {
  InputSet in = uniform_points(40000, 11);
  add_dt_edge_constraints(in, 10000, 0.2, 6);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  ResolveProgress progress;
  std::atomic<int> too_early{0}, before_the_end{0};
  const TileTriangulator checked = [&](const Points& v, const std::vector<Edge>& s, std::string_view what) {
    const double b = progress.clean_below.load();
    if (!(b == kInf || v.back().x < b)) ++too_early;
    if (b != kInf) ++before_the_end;
    return cgal_tile_triangulator()(v, s, what);
  };
  std::thread clearing([&] {
    const double lo = p.vertices.front().x, hi = p.vertices.back().x;
    for (int k = 1; k < 10; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      progress.publish(lo + (hi - lo) * k / 10, false);
    }
    for (int waited = 0; before_the_end.load() == 0 && waited < 1000; ++waited)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    progress.publish(kInf, false);
  });
  TileOptions opt;
  opt.max_tile_points = 1000;
  const std::optional<Triangles> t = tiled_cdt_ahead(p, progress, opt, checked);
  clearing.join();
  ASSERT_TRUE(t.has_value());
  EXPECT_TRUE(*t == single.mesh.triangles);
  EXPECT_EQ(too_early.load(), 0);
  EXPECT_GT(before_the_end.load(), 0) << "no tile began before the input was cleared everywhere";
}

// Ranks (MPI) give up before their exchange: a rank whose tiles all lie below the first event would otherwise
// wait there for ranks that gave up. Rank 0 of 2 holds the left of two slabs, cleared at once; the event is
// found while that slab is being triangulated.
TEST(TilesAhead, RanksGiveUpBeforeTheirExchange) {
  InputSet in = uniform_points(20000, 13);
  add_dt_edge_constraints(in, 5000, 0.2, 8);
  const PreparedInput p = prepare(in);
  ResolveProgress progress;
  const double lo = p.vertices.front().x, hi = p.vertices.back().x;
  progress.publish(lo + (hi - lo) * 0.75, false);
  int exchanges = 0;
  TileSharing sharing;
  sharing.rank = 0;
  sharing.ranks = 2;
  sharing.gather = [&](std::vector<uint32_t>) {
    ++exchanges;
    return std::vector<std::vector<uint32_t>>{};
  };
  TileOptions opt;
  opt.max_tile_points = p.vertices.size() / 2 + 1;
  opt.shape = TileShape::slabs;
  opt.sharing = &sharing;
  int tiles = 0;
  const TileTriangulator counted = [&](const Points& v, const std::vector<Edge>& s, std::string_view what) {
    ++tiles;
    progress.publish(-kInf, true);  // the resolve finds an event meanwhile
    return cgal_tile_triangulator()(v, s, what);
  };
  const std::optional<Triangles> t = tiled_cdt_ahead(p, progress, opt, counted);
  EXPECT_FALSE(t.has_value());
  EXPECT_EQ(tiles, 1) << "rank 0's slab, cleared at once";
  EXPECT_EQ(exchanges, 0) << "the rank went to the exchange although the resolve changes the input";
}

TEST(TilesAhead, CrossingConstraintsDropTheEarlyTiles) {
  const PreparedInput p = prepare(tile_layouts::crossing_constraints());
  const CdtResult single = triangulate_cgal(p);
  ASSERT_GT(single.steiner_points, 0u);
  for (uint64_t tp : {16, 200}) {
    AheadRun run = run_ahead(p, tp);
    EXPECT_FALSE(run.ahead.has_value()) << "tiles of " << tp;
    EXPECT_EQ(run.too_early, 0) << "tiles of " << tp;
    ASSERT_FALSE(run.resolved.unchanged);
    TileOptions opt;
    opt.max_tile_points = tp;
    const CdtResult tiled = triangulate_tiled(std::move(run.resolved), opt, cgal_tile_triangulator());
    EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices);
    EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << "tiles of " << tp;
  }
}

TEST(ResolveProgress, ClearedXGrowsAndEndsAtInfinityOnlyWhenNothingIsSplit) {
  InputSet clean = uniform_points(200000, 3);
  add_dt_edge_constraints(clean, 50000, 0.2, 5);
  for (const auto& [name, in, splits] :
       {std::tuple{"clean", clean, false}, std::tuple{"crossing", tile_layouts::crossing_constraints(), true}}) {
    const PreparedInput p = prepare(in);
    ResolveProgress progress;
    std::atomic<bool> done{false}, shrank{false};
    std::thread watcher([&] {
      double last = -kInf;
      while (!done.load()) {
        const double now = progress.clean_below.load();
        if (now < last) shrank = true;
        last = now;
      }
    });
    const int nice_before = getpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)));
    const ResolvedInput r = resolve_if_needed(p, progress, 2);
    done = true;
    watcher.join();
    EXPECT_EQ(getpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid))), nice_before)
        << name << ": only the resolve's own threads run at a lower priority";
    EXPECT_FALSE(shrank.load()) << name;
    EXPECT_EQ(r.unchanged, !splits) << name;
    EXPECT_EQ(progress.changes.load(), splits) << name;
    EXPECT_EQ(progress.wait_clean(kInf), !splits) << name;
    if (splits) {
      const ResolvedInput copy = resolve_constraints(p, 2);
      EXPECT_EQ(r.vertices, copy.vertices) << name;
      EXPECT_EQ(r.constraints, copy.constraints) << name;
      EXPECT_EQ(r.steiner_points, copy.steiner_points) << name;
    } else {
      EXPECT_EQ(progress.clean_below.load(), kInf) << name;
    }
  }
}

// The resolve's side: while it has reported no event, what it says it cleared lies below every event. Two
// short segments crossing each other (and the constraints in their way) at x0 + 7400..7600 of a clean input:
// nothing may be cleared past x0 + 7500 before the events there are reported.
TEST(ResolveProgress, NeverClearsPastAnEventBeforeReportingIt) {
  InputSet in = uniform_points(200000, 9);
  add_dt_edge_constraints(in, 50000, 0.2, 4);
  const double x0 = kUniformX0, y0 = kUniformY0;
  in.lines.push_back({{{x0 + 7400.25, y0 + 5000.25, 0}, {x0 + 7600.25, y0 + 5200.25, 0}}});
  in.lines.push_back({{{x0 + 7400.25, y0 + 5200.25, 0}, {x0 + 7600.25, y0 + 5000.25, 0}}});
  const PreparedInput p = prepare(in);
  for (int round = 0; round < 3; ++round) {
    ResolveProgress progress;
    std::atomic<bool> done{false};
    std::atomic<double> worst{-kInf};  // the most cleared while no event was reported
    std::thread watcher([&] {
      while (!done.load()) {
        const double b = progress.clean_below.load();
        const bool c = progress.changes.load();  // read after b: publish sets it before it raises b
        if (!c && b > worst.load()) worst = b;
      }
    });
    const ResolvedInput r = resolve_if_needed(p, progress, 2);
    done = true;
    watcher.join();
    ASSERT_FALSE(r.unchanged);
    EXPECT_LE(worst.load(), x0 + 7500) << "cleared past the crossing before reporting it";
    EXPECT_TRUE(progress.changes.load());
  }
}

}  // namespace
}  // namespace cdtgpu
