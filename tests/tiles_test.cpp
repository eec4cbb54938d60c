// The tiled CDT (core/tiles): with tiles of 16 to 500 points, on uniform, clustered, grid and degenerate
// layouts, with crossing and long constraints, the mesh equals triangulate_cgal's (the single run) exactly;
// the tiles' counts say the path really tiled.
#include "core/tile_workers.hpp"
#include "core/tiles.hpp"
#include "core/tile_plan.hpp"

#include <CGAL/Exact_rational.h>
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/workloads.hpp"
#include "io/readers.hpp"
#include "tests/peer_inputs.hpp"
#include "tests/tile_layouts.hpp"

namespace cdtgpu {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using tile_layouts::line;
using tile_layouts::random_points;

// CGAL's triangles without their neighbours, as the GPU gives them: the tiles find their border themselves.
TileTriangulator without_neighbours() {
  return [](const Points& v, const std::vector<Edge>& s, std::string_view what) {
    TileMesh m = cgal_tile_triangulator()(v, s, what);
    m.neighbours.clear();
    return m;
  };
}

// The tiled mesh against the single run, at several tile sizes, with and without the triangulator's
// neighbours, as slabs and as slabs whose first and last are cut into three (TileOptions::ramp); returns the
// stats of the smallest tiles.
TileStats expect_same_as_single_run(const InputSet& in, std::vector<uint64_t> tile_points = {16, 50, 500}) {
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  TileStats smallest;
  for (uint64_t tp : tile_points)
    for (const int variant : {0, 1, 2, 3}) {  // with the triangulator's neighbours, without them, slabs, ramped
      const bool neighbours = variant != 1;
      SCOPED_TRACE(variant == 0   ? "with neighbours"
                   : variant == 1 ? "without neighbours"
                   : variant == 2 ? "slabs"
                                  : "slabs with a ramp of 3");
      TileStats ts;
      TileOptions opt;
      opt.max_tile_points = tp;
      opt.shape = variant >= 2 ? TileShape::slabs : TileShape::automatic;
      opt.ramp = variant == 3 ? 3 : 0;
      const CdtResult tiled = triangulate_tiled(
          resolve_constraints(p), opt, neighbours ? cgal_tile_triangulator() : without_neighbours(), &ts);
      EXPECT_EQ(tiled.steiner_points, single.steiner_points) << "tiles of " << tp;
      EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << "tiles of " << tp;
      EXPECT_EQ(tiled.mesh.triangles.size(), single.mesh.triangles.size()) << "tiles of " << tp;
      EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << "tiles of " << tp;
      if (p.vertices.size() > tp) {
        EXPECT_GE(ts.tiles, 2u) << "tiles of " << tp;
      }
      if (tp == tile_points.front() && variant == 0) smallest = ts;
    }
  return smallest;
}

TEST(Tiles, UniformPointsWithoutConstraints) {
  const TileStats ts = expect_same_as_single_run(random_points(3000, 1));
  EXPECT_GT(ts.final_triangles, 0u);
}

TEST(Tiles, UniformWithDelaunayEdgeConstraints) {
  InputSet in = uniform_points(4000, 7);
  add_dt_edge_constraints(in, 300, 0.05, 3);  // long ones: about 5 spacings each
  expect_same_as_single_run(in);
}

TEST(Tiles, CrossingConstraintsResolvedFirst) { expect_same_as_single_run(tile_layouts::crossing_constraints()); }

TEST(Tiles, OneConstraintCrossesEveryTile) {
  expect_same_as_single_run(tile_layouts::constraints_across_every_tile());
}

TEST(Tiles, LongConstraintsWhoseCirclesSpanManyTiles) {
  expect_same_as_single_run(tile_layouts::long_nearly_parallel_constraints());
}

TEST(Tiles, DemGridCoCircularEverywhere) { expect_same_as_single_run(tile_layouts::dem_grid(), {16, 40, 100, 400}); }

TEST(Tiles, GridWithContoursAndBordersOnGridLines) {
  expect_same_as_single_run(tile_layouts::terrain_with_contours(), {16, 64, 500});
}

TEST(Tiles, DuplicatesOnBothSidesOfABorder) { expect_same_as_single_run(tile_layouts::duplicates_on_both_sides()); }

TEST(Tiles, ClusteredPoints) { expect_same_as_single_run(tile_layouts::clustered_points()); }

TEST(Tiles, CollinearAndNearlyCollinearRows) { expect_same_as_single_run(tile_layouts::collinear_rows()); }

TEST(Tiles, AllCollinearGivesNoTriangles) { expect_same_as_single_run(tile_layouts::all_collinear()); }

TEST(Tiles, FootprintRingsAcrossTiles) { expect_same_as_single_run(tile_layouts::footprint_rings()); }

TEST(Tiles, SingleTileIsTheUntiledRun) {
  InputSet in = random_points(200, 12);
  const PreparedInput p = prepare(in);
  TileStats ts;
  TileOptions opt;
  opt.max_tile_points = 1000;
  const CdtResult tiled = triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator(), &ts);
  EXPECT_EQ(ts.tiles, 0u);
  EXPECT_TRUE(tiled.mesh.triangles == triangulate_cgal(p).mesh.triangles);
}

TEST(Tiles, MergeTiledAgainOnLargerInputs) {
  InputSet in = uniform_points(30000, 21);
  add_dt_edge_constraints(in, 3000, 0.2, 4);
  const TileStats ts = expect_same_as_single_run(in, {1000});
  EXPECT_GE(ts.levels, 2u) << "the merge should have been tiled again";
  EXPECT_LT(ts.merge_vertices, 30000u / 2);
}

// Columns of over 2^20 vertices are cut by the parallel selection (two sampled pivots, then nth_element in
// the band between them): the same triangles.
TEST(Tiles, LargeColumnsCutByTheParallelSelection) {
  InputSet in = uniform_points(1'100'000, 31);
  const TileStats ts = expect_same_as_single_run(in, {600'000});
  EXPECT_EQ(ts.tiles, 2u);
}

TEST(Tiles, SameTrianglesWhateverTheTilesInFlight) {
  InputSet in = random_points(2000, 13);
  const PreparedInput p = prepare(in);
  TileOptions all;
  all.max_tile_points = 100;
  const CdtResult b = triangulate_tiled(resolve_constraints(p), all, cgal_tile_triangulator());
  for (const unsigned in_flight : {1u, 2u, 3u}) {
    TileOptions some = all;
    some.tiles_in_flight = in_flight;
    const CdtResult a = triangulate_tiled(resolve_constraints(p), some, cgal_tile_triangulator());
    EXPECT_TRUE(a.mesh.triangles == b.mesh.triangles) << in_flight << " in flight";
  }
}

// A tile that fails stops the others, but a tile already in flight runs whole: its own parallel loops are not
// cancelled halfway (through TBB's cancellation a GPU tile then ran its device call on half-written input).
TEST(Tiles, AFailingTileLeavesTheTilesInFlightWhole) {
  InputSet in = random_points(2000, 13);
  TileOptions opt;
  opt.max_tile_points = 100;
  opt.tiles_in_flight = 2;
  std::atomic<bool> started{false}, thrown{false};
  std::atomic<int> loops{0}, partial{0};
  auto wait_for = [](const std::atomic<bool>& flag) {
    for (int i = 0; i < 400 && !flag.load(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  };
  opt.finalize = [&](const TileJob& job) {
    if (job.what.starts_with("tile 1 of")) {
      wait_for(started);
      thrown = true;
      throw std::runtime_error("tile 1 fails");
    }
    started = true;
    wait_for(thrown);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the error reaches the tiles' loop
    std::atomic<int> done{0};
    tbb::parallel_for(0, 10000, 1, [&](int) { ++done; });
    ++loops;
    if (done != 10000) ++partial;
    return TileFinal{};
  };
  try {
    triangulate_tiled(resolve_constraints(prepare(in)), opt, cgal_tile_triangulator());
    ADD_FAILURE() << "the failing tile's error was lost";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "tile 1 fails");
  }
  EXPECT_EQ(partial.load(), 0) << "of " << loops.load() << " tiles in flight";
}

// Tiles run by other processes (core/tile_workers.hpp, as MPI ranks run them): each worker gets a tile's
// vertices and segments only, as they travel, and answers in the tile's ids. The same triangles as the single
// run; every worker takes tiles, never two in one slot at once, and this process never more than its own slots.
TEST(Tiles, TilesRunByWorkersGiveTheSingleRun) {
  InputSet in = random_points(3000, 41);
  in.lines.push_back(line({{-10, 500, 0}, {1010, 480, 0}}));  // crosses many tiles
  in.lines.push_back(line({{500, -10, 0}, {520, 1010, 0}}));
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const TileFinalizer host = host_finalizer(cgal_tile_triangulator());
  for (const std::vector<unsigned>& slots : {std::vector<unsigned>{1}, std::vector<unsigned>{2, 3}}) {
    std::vector<std::vector<std::atomic<bool>>> busy;
    for (unsigned n : slots) busy.emplace_back(n);
    std::vector<std::atomic<int>> taken(slots.size());
    std::atomic<bool> twice{false};
    TileWorkers workers;
    workers.slots = slots;
    workers.run = [&](unsigned w, unsigned slot, const TileWork& sent) {
      if (busy[w][slot].exchange(true)) twice = true;
      TileWork got = sent;  // what arrives: nothing of the whole input
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // the transfers: other tiles begin meanwhile
      TileFinal f = host(got.job());
      ++taken[w];
      busy[w][slot] = false;
      return f;
    };
    std::atomic<int> here{0}, most_here{0};
    const TileFinalizer local = [&](const TileJob& job) {
      const int now = ++here;
      for (int m = most_here; now > m && !most_here.compare_exchange_weak(m, now);) {
      }
      TileFinal f = host(job);
      --here;
      return f;
    };
    TileOptions opt;
    opt.max_tile_points = 100;
    opt.shape = TileShape::squares;
    opt.finalize = with_workers(local, 2, workers);
    opt.waiting_threads = workers.total_slots();
    TileStats ts;
    const CdtResult r = triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator(), &ts);
    EXPECT_GE(ts.tiles, 16u);
    EXPECT_EQ(r.mesh.vertices, single.mesh.vertices);
    EXPECT_TRUE(r.mesh.triangles == single.mesh.triangles) << slots.size() << " workers";
    for (size_t w = 0; w < slots.size(); ++w) EXPECT_GT(taken[w].load(), 0) << "worker " << w;
    EXPECT_FALSE(twice.load());
    EXPECT_LE(most_here.load(), 2);
  }
}

// A worker's tile that finds segments to resolve fails the tiling here as a tile of this process would, so the
// caller resolves and tiles again.
TEST(Tiles, AWorkersUnresolvedTileFailsTheTiling) {
  const PreparedInput p = prepare(random_points(2000, 43));
  TileWorkers workers;
  workers.slots = {2};
  workers.run = [](unsigned, unsigned, const TileWork& work) -> TileFinal {
    throw UnresolvedTile(work.what + ": two segments cross");
  };
  TileOptions opt;
  opt.max_tile_points = 100;
  opt.finalize = with_workers(host_finalizer(cgal_tile_triangulator()), 1, workers);
  opt.waiting_threads = 2;
  EXPECT_THROW(triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator()), UnresolvedTile);
}

// The final-triangle test never says inside when the exact answer is no: random, flat and huge triangles at
// UTM offsets, against rectangles whose sides sit at the exact circle's extremes and a hair beside them.
TEST(Tiles, CircumdiskTestIsNeverWrongAboutInside) {
  using Q = CGAL::Exact_rational;
  std::mt19937_64 rng(17);
  auto exact = [](const Point3& a, const Point3& b, const Point3& c, double x0, double x1, double y0,
                  double y1) {
    const Q bx = Q(b.x) - Q(a.x), by = Q(b.y) - Q(a.y), cx = Q(c.x) - Q(a.x), cy = Q(c.y) - Q(a.y);
    const Q d = 2 * (bx * cy - by * cx);
    if (d == 0) return false;
    const Q b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
    const Q ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d, r2 = ux * ux + uy * uy;
    auto clear = [&](const Q& gap) { return gap > 0 && gap * gap > r2; };
    return (std::isinf(x0) || clear(Q(a.x) + ux - Q(x0))) && (std::isinf(x1) || clear(Q(x1) - Q(a.x) - ux)) &&
           (std::isinf(y0) || clear(Q(a.y) + uy - Q(y0))) && (std::isinf(y1) || clear(Q(y1) - Q(a.y) - uy));
  };
  int inside = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::ldexp(1.0, int(uniform_below(rng, 40)) - 20);
    const Point3 a{500000 + unit_double(rng) * 1000, 6000000 + unit_double(rng) * 1000, 0};
    Point3 b{a.x + (unit_double(rng) - 0.5) * scale, a.y + (unit_double(rng) - 0.5) * scale, 0};
    Point3 c{a.x + (unit_double(rng) - 0.5) * scale, a.y + (unit_double(rng) - 0.5) * scale, 0};
    if (i % 3 == 0)
      c = {b.x + (b.x - a.x) * 0.75, b.y + (b.y - a.y) * 0.75 + scale * 1e-12 * (i % 7), 0};  // flat
    // The circle's extremes in doubles, then sides at them and a few ulps inside and outside.
    const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y, d = 2 * (bx * cy - by * cx);
    if (d == 0) continue;
    const double ux = (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d;
    const double uy = (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d;
    const double r = std::hypot(ux, uy);
    for (int k = -3; k <= 3; ++k) {
      const double nudge = k * 4e-16 * (std::abs(a.x) + r);
      const double x0 = a.x + ux - r - nudge, x1 = a.x + ux + r + nudge;
      const double y0 = a.y + uy - r - nudge, y1 = a.y + uy + r + nudge;
      const bool got = circumdisk_inside(a, b, c, x0, x1, y0, y1);
      ASSERT_FALSE(got && !exact(a, b, c, x0, x1, y0, y1)) << i << " " << k;
      const bool wide = circumdisk_inside(a, b, c, x0 - r, kInf, -kInf, y1 + r);
      ASSERT_FALSE(wide && !exact(a, b, c, x0 - r, kInf, -kInf, y1 + r)) << i;
      inside += wide;
      ++checked;
    }
  }
  EXPECT_GT(inside, checked / 2) << "the test should rarely give up on clear cases";
}

TEST(Tiles, AutoTileSizeForTheCpu) {
  EXPECT_EQ(auto_cpu_tile_points(5'000'000, 1), 0u);
  EXPECT_EQ(auto_cpu_tile_points(1000, 16), 0u);
  EXPECT_GT(auto_cpu_tile_points(2'000'000, 2), 0u);
  EXPECT_LT(auto_cpu_tile_points(2'000'000, 2), 2'000'000u);
  EXPECT_EQ(auto_cpu_tile_points(1'000'000'000, 16), 1'000'000u);  // at most 1M: faster, and less in flight
}

// GPU tiles: a quarter of the input on one device; on several a twelfth a device, but at least 2^25 points and a
// 64th of the input, at most a quarter a device; at most what the smallest device holds (1B LAS points + 250M
// contour vertices: 134M on one H200, 52M on two, 2^25 on four and eight).
TEST(Tiles, AutoTileSizeForGpus) {
  const uint64_t h200 = 134'217'726;
  const uint64_t least = uint64_t(1) << 25;
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, h200, 1), h200);
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, h200, 2), 52'083'334u);  // 24 slabs: n / 24
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, h200, 4), least);         // n / 64 would be under 2^25
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, h200, 8), least);
  EXPECT_EQ(auto_gpu_tile_points(10'000'000'000, h200, 8), h200);         // at most the device's
  EXPECT_EQ(auto_gpu_tile_points(5'000'000'000, h200, 8), 78'125'001u);   // n / 64: at most 64 slabs
  EXPECT_EQ(auto_gpu_tile_points(200'000'000, h200, 1), 50'000'001u);
  EXPECT_EQ(auto_gpu_tile_points(400'000'000, h200, 2), least);           // under a quarter a device (50M)
  EXPECT_EQ(auto_gpu_tile_points(100'000'000, h200, 2), 12'500'001u);     // a quarter a device is less than 2^25
  EXPECT_EQ(auto_gpu_tile_points(1'000, 100, 0), 100u);  // no device counted: as one
  // The shape such tiles take on a square input: slabs up to 64 of them, squares beyond, and for small tiles.
  EXPECT_TRUE(auto_slabs(32, 39'062'501, 1000, 1000));
  EXPECT_TRUE(auto_slabs(64, least, 1000, 1000));
  EXPECT_FALSE(auto_slabs(65, least, 1000, 1000));
  EXPECT_TRUE(auto_slabs(16, least, 1000, 4000));   // four times as tall as wide: 16 slabs, each 64 times
  EXPECT_FALSE(auto_slabs(17, least, 1000, 4000));
  EXPECT_FALSE(auto_slabs(32, 1'000'000, 1000, 1000));  // a CPU-sized tile
}

// Under MPI rank 0 sizes GPU tiles for every rank's GPUs (their GPU slots, two a device); other ranks and a run
// without ranks count their own.
TEST(Tiles, GpuTilesAreSizedForEveryRanksDevices) {
  RankTiles ranks;
  ranks.ranks = 4;
  ranks.workers = [](bool gpu) {
    TileWorkers w;
    w.slots = gpu ? std::vector<unsigned>{2, 4, 0} : std::vector<unsigned>{16, 16, 16};
    return w;
  };
  EXPECT_EQ(run_gpu_devices(1, &ranks), 4u);  // its own, one on the second rank, two on the third, none on the fourth
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, 134'217'726, run_gpu_devices(1, &ranks)), uint64_t(1) << 25);
  ranks.rank = 2;
  EXPECT_EQ(run_gpu_devices(1, &ranks), 1u);
  EXPECT_EQ(run_gpu_devices(2, nullptr), 2u);
  // Before the workers' slots are known (the devices opened while rank 0 prepares), at every rank: each rank
  // counted as this one, so ranks bound one to a GPU size their pools for the tiles rank 0 will plan.
  EXPECT_EQ(expected_gpu_devices(1, &ranks), 4u);
  EXPECT_EQ(expected_gpu_devices(2, &ranks), 8u);
  EXPECT_EQ(expected_gpu_devices(2, nullptr), 2u);
  ranks.ranks = 2, ranks.rank = 0;
  ranks.workers = [](bool gpu) {
    TileWorkers w;
    w.slots = {gpu ? 2u : 16u};
    return w;
  };
  EXPECT_EQ(auto_gpu_tile_points(1'250'000'000, 134'217'726, expected_gpu_devices(1, &ranks)),
            auto_gpu_tile_points(1'250'000'000, 134'217'726, run_gpu_devices(1, &ranks)));
}

// TileOptions::tiles_done: called once, after every first-level tile and before any merge (a GPU run frees its
// other devices and staging there), whatever the levels; the triangles stay the single run's.
TEST(Tiles, TilesDoneComesBetweenTheTilesAndTheMerge) {
  InputSet in = random_points(3000, 17);
  in.lines.push_back(line({{-10, 500, 0}, {1010, 480, 0}}));
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const TileFinalizer host = host_finalizer(cgal_tile_triangulator());
  const TileTriangulator cgal = cgal_tile_triangulator();
  for (const double share : {0.0, 1.0}) {  // one level; a merge tiled again
    std::mutex m;
    std::vector<std::string> calls;
    auto note = [&](std::string what) {
      std::lock_guard<std::mutex> lock(m);
      calls.push_back(std::move(what));
    };
    TileOptions opt;
    opt.max_tile_points = 300;
    opt.retile_share = share;
    opt.tiles_in_flight = 4;
    opt.finalize = [&](const TileJob& job) {
      note(job.what.ends_with("level 1") ? "tile" : "later tile");
      return host(job);
    };
    opt.tiles_done = [&] { note("done"); };
    TileStats ts;
    const CdtResult tiled = triangulate_tiled(
        resolve_constraints(p), opt,
        [&](const Points& v, const std::vector<Edge>& e, std::string_view what) {
          note("merge");
          return cgal(v, e, what);
        },
        &ts);
    EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << "retile share " << share;
    const auto done = std::find(calls.begin(), calls.end(), "done");
    ASSERT_NE(done, calls.end()) << "retile share " << share;
    EXPECT_EQ(std::count(calls.begin(), calls.end(), "done"), 1) << "retile share " << share;
    EXPECT_GT(std::count(calls.begin(), done, "tile"), 1) << "retile share " << share;
    EXPECT_EQ(std::count(done, calls.end(), "tile"), 0) << "retile share " << share;
    EXPECT_EQ(std::count(calls.begin(), done, "later tile"), 0) << "retile share " << share;
    EXPECT_EQ(std::count(calls.begin(), done, "merge"), 0) << "retile share " << share;
    EXPECT_GE(std::count(done, calls.end(), "merge"), 1) << "retile share " << share;
    if (share > 0) {
      EXPECT_GT(std::count(done, calls.end(), "later tile"), 0) << "the merge was to be tiled again";
    }
  }
}

// Four tiles a core, exactly, on data about as wide as tall: 2 cores 2 x 4 tiles (not 3 x 3), 16 cores 8 x 8
// (not 80 of the size rounded down). A ninth tile on 2 cores runs alone.
TEST(Tiles, AutoTileSizeGivesFourTilesACore) {
  InputSet in = uniform_points(1'300'000, 33);  // 64 tiles above the 20K-point floor
  const PreparedInput p = prepare(in);
  const uint64_t n = p.vertices.size();
  for (const unsigned cores : {2u, 16u}) {
    TileOptions opt;
    opt.max_tile_points = auto_cpu_tile_points(n, cores);
    opt.retile_share = 0;  // the first level alone
    TileStats ts;
    triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator(), &ts);
    EXPECT_EQ(ts.tiles, 4u * cores) << cores << " cores, tiles of " << opt.max_tile_points;
  }
}

// The peer inputs (artem-ogre/CDT's test suite) when ../shared/data is there: every one, tiles of 16 and 64.
TEST(Tiles, PeerInputs) {
  CDTGPU_SKIP_WITHOUT_PEER_INPUTS();
  int files = 0;
  for (const auto& path : peer_input_files()) {
    std::ifstream file(path, std::ios::binary);
    InputSet in;
    read_peer_input(file, path.string(), in);
    SCOPED_TRACE(path.filename().string());
    expect_same_as_single_run(in, {16, 64});
    ++files;
  }
  EXPECT_GT(files, 0);
}

}  // namespace
}  // namespace cdtgpu
