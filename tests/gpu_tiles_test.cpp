// GPU tiles on several devices (gpu/devices, gpu/tile_triangulator): two contexts on the test machine's device
// (lavapipe in CI) stand for two GPUs. The tiled mesh equals the single CGAL run's whatever device takes which
// tile; --devices lists are checked; a device that fails a tile is named.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/tiles.hpp"
#include "core/tiles_ahead.hpp"
#include "core/verify.hpp"
#include "core/workloads.hpp"
#include "gpu/check.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/devices.hpp"
#include "gpu/tile_triangulator.hpp"
#include "tests/tile_layouts.hpp"

namespace cdtgpu {
namespace {

size_t test_device() { return gpu::pick_device(gpu::list_devices(), ""); }

TEST(GpuTiles, TwoDevicesGiveTheSingleRunsBytes) {
  InputSet in = uniform_points(20000, 7);
  add_dt_edge_constraints(in, 5000, 0.5, 7);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const size_t d = test_device();
  const auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
  for (bool on_device : {false, true})
    for (unsigned in_flight : {2u, 4u}) {
      TileOptions opt;
      opt.max_tile_points = 2500;
      opt.tiles_in_flight = in_flight;
      TileStats ts;
      gpu::GpuCdtStats sum;
      gpu::GpuTiles tiles = gpu::gpu_tiles({&a, &b}, &sum);
      if (on_device) opt.finalize = tiles.finalize, opt.reserve = tiles.reserve;
      if (in_flight == 4) opt.shape = TileShape::slabs, opt.ramp = 2;  // as bench --tile-ramps 2
      const CdtResult tiled = triangulate_tiled(resolve_constraints(p), opt, tiles.triangulate, &ts);
      const std::string what = std::to_string(in_flight) + " in flight, final test on the " +
                               (on_device ? "device" : "host") + (in_flight == 4 ? ", ramped slabs" : "");
      EXPECT_GE(ts.tiles, 8u);
      EXPECT_GT(sum.wall_total_ms, 0.0);
      EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << what;
      EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << what;
    }
}

// GpuTiles::tiles_done, as cdtgpu triangulate passes it: the tiles on two devices with memory pools, then every
// slot but the first and the second device's pool freed beside the merge, which runs on what is left. The single
// run's bytes, and again from a second run on the same tiles (one slot, one device: later calls still work).
TEST(GpuTiles, TilesDoneFreesWhatTheMergeDoesNotNeed) {
  InputSet in = uniform_points(12000, 9);
  add_dt_edge_constraints(in, 3000, 0.5, 9);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const size_t d = test_device();
  const auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  for (const auto& c : ctxs) c->memory_pool.store(gpu::make_device_pool(*c, uint64_t(1) << 30));
  const std::weak_ptr<gpu::DeviceMemoryPool> second = ctxs[1]->memory_pool.load();
  {
    const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
    std::optional<gpu::GpuTiles> tiles = gpu::gpu_tiles({&a, &b}, nullptr, /*warm_up_from=*/UINT64_MAX, /*pools_from=*/0);
    for (int run = 0; run < 2; ++run) {
      TileOptions opt;
      opt.max_tile_points = 2000;
      opt.tiles_in_flight = 4;
      opt.finalize = tiles->finalize, opt.reserve = tiles->reserve, opt.tiles_done = tiles->tiles_done;
      TileStats ts;
      const CdtResult tiled = triangulate_tiled(resolve_constraints(p), opt, tiles->triangulate, &ts);
      EXPECT_GE(ts.tiles, 6u) << "run " << run;
      EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << "run " << run;
      EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << "run " << run;
    }
    tiles.reset();  // joins the frees
    EXPECT_TRUE(ctxs[0]->memory_pool.load()) << "the first device keeps its pool for the merge";
    EXPECT_FALSE(ctxs[1]->memory_pool.load()) << "the second device's pool is let go once the tiles are done";
    EXPECT_TRUE(second.expired()) << "no buffer of the second device holds its pool: its memory is freed";
  }
}

// A warm-up makes the constraint inserter's buffers too (its tile carries segments): without them the first real
// tiles grew the device's memory pool while they held the device.
TEST(GpuTiles, AWarmUpMakesTheConstraintInsertersBuffers) {
  const auto ctxs = gpu::create_contexts({test_device()}, gpu::ContextOptions{});
  const gpu::GpuCdt cdt(*ctxs[0]);
  EXPECT_FALSE(cdt.keeps("cdt constrained bits"));
  gpu::HostStaging staging;
  cdt.warm_up_tiles(20000, staging);
  EXPECT_TRUE(cdt.keeps("cdt constrained bits"));
  EXPECT_TRUE(cdt.keeps("tri_verts"));
}

// Devices warmed up for the tiles before the resolve (as cdtgpu triangulate reserves them), each with a device
// memory pool, both forced here on the test's device: every device warmed up once, its buffers taken from its
// pool, the single run's bytes, and a second run (buffers kept, no second warm-up or pool) the same.
TEST(GpuTiles, WarmedUpDevicesGiveTheSingleRunsBytes) {
  InputSet in = uniform_points(12000, 5);
  add_dt_edge_constraints(in, 3000, 0.5, 5);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const size_t d = test_device();
  const auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
  gpu::GpuTiles tiles = gpu::gpu_tiles({&a, &b}, nullptr, /*warm_up_from=*/0, /*pools_from=*/0);
  for (int run = 0; run < 2; ++run) {
    TileOptions opt;
    opt.max_tile_points = 2000;
    opt.tiles_in_flight = 4;
    // The second run as cdtgpu triangulate runs warmed-up tiles: slabs, the first and the last cut in two.
    if (run == 1) opt.shape = TileShape::slabs, opt.ramp = 2;
    opt.finalize = tiles.finalize, opt.reserve = tiles.reserve;
    tiles.reserve(tile_staging_points(p.vertices.size(), opt.max_tile_points));
    // A warm-up is skipped once a tile has begun: waited for here, so that the test does not race it.
    for (int i = 0; i < 6000 && tiles.warm_ups() < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const CdtResult tiled = triangulate_tiled(resolve_constraints(p), opt, tiles.triangulate);
    EXPECT_EQ(tiles.warm_ups(), 2u) << "run " << run;
    EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << "run " << run;
    EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << "run " << run;
    tiles.hold_clocks();  // as the tiles bench between its runs: the next run's tiles take the devices from it
  }
  std::vector<std::shared_ptr<gpu::DeviceMemoryPool>> pools;
  for (const auto& c : ctxs) pools.push_back(c->memory_pool.load());
  for (size_t i = 0; i < pools.size(); ++i) {
    ASSERT_TRUE(pools[i]) << "device " << i;
    EXPECT_GE(pools[i]->bytes(), tile_staging_points(p.vertices.size(), 2000) * 260) << "device " << i;
    EXPECT_GT(pools[i]->ranges_taken(), 10u) << "device " << i;
  }
  // The default: never on a CPU device, 100M points on hardware GPUs (pools from 8M); the ramp where they warm up.
  const bool cpu = a.context().info.type == "cpu";
  EXPECT_EQ(gpu::warm_up_from({&a}), cpu ? UINT64_MAX : uint64_t(100'000'000));
  EXPECT_EQ(gpu::warm_up_from({&a, &a}), cpu ? UINT64_MAX : uint64_t(50'000'000));  // several: tiles shrink with them
  EXPECT_EQ(gpu::tile_ramp({&a, &a}, 60'000'000), 0u);  // warmed up, but the ramp is for tiles of 100M or more
  EXPECT_EQ(gpu::device_pools_from({&a}), cpu ? UINT64_MAX : uint64_t(8'000'000));
  EXPECT_EQ(gpu::tile_ramp({&a}, 134'000'000), cpu ? 0u : 2u);
  EXPECT_EQ(gpu::tile_ramp({&a}, 20'000'000), 0u);
}

// The device's final triangles of one tile against the host's test on the same CDT: never one the host does not
// take (its test is checked against exact rationals in tiles_test), nearly all of them, and the border the
// final set has. Grid points with the rectangle's sides on grid lines put many circles exactly on a side.
void expect_final_within_host(const gpu::GpuCdt& cdt, const Points& all, const std::vector<Edge>& segments,
                              const TileRect& rect, const std::string& what) {
  std::vector<uint32_t> ids(all.size());
  for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
  const TileFinal f = cdt.finalize_tile(TileJob{all, ids, segments, rect, what});
  Triangles cdt_all = cdt_of_graph(all, segments);
  canonicalize_triangles(cdt_all);
  Triangles host;
  for (const Triangle& t : cdt_all)
    if (circumdisk_inside(all[t[0]], all[t[1]], all[t[2]], rect.x0, rect.x1, rect.y0, rect.y1)) host.push_back(t);
  ASSERT_TRUE(std::is_sorted(f.triangles.begin(), f.triangles.end())) << what;
  EXPECT_TRUE(std::includes(host.begin(), host.end(), f.triangles.begin(), f.triangles.end())) << what;
  EXPECT_GE(f.triangles.size(), host.size() * 95 / 100) << what;
  EXPECT_GT(f.triangles.size(), 0u) << what;
  std::set<Edge> edges, border;
  for (const Triangle& t : f.triangles)
    for (int k = 0; k < 3; ++k) edges.insert({t[k], t[(k + 1) % 3]});
  for (const Edge& e : edges)
    if (!edges.count({e[1], e[0]})) border.insert(e);
  EXPECT_EQ(std::vector<Edge>(border.begin(), border.end()), f.border) << what;
}

TEST(GpuTiles, DeviceFinalTestIsWithinTheHostsTest) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  InputSet in = uniform_points(6000, 11);
  add_dt_edge_constraints(in, 1500, 0.5, 11);
  const ResolvedInput r = resolve_constraints(prepare(in));
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const Point3& v : r.vertices) x0 = std::min(x0, v.x), x1 = std::max(x1, v.x), y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
  const double w = x1 - x0, h = y1 - y0;
  expect_final_within_host(cdt, r.vertices, r.constraints, TileRect{x0 + w / 4, x1 - w / 4, y0 + h / 5, y1 - h / 3}, "uniform, inner");
  expect_final_within_host(cdt, r.vertices, r.constraints, TileRect{-std::numeric_limits<double>::infinity(), x0 + w / 2, y0 + h / 2, std::numeric_limits<double>::infinity()}, "uniform, a corner tile");
  // More segments than points (nearly every Delaunay edge a segment): not staged behind the points, but
  // uploaded inside the device's call as a whole run's are (GpuCdt::upload_tile).
  InputSet dense = uniform_points(2000, 12);
  add_dt_edge_constraints(dense, 5000, 1.0, 12);
  const ResolvedInput d = resolve_constraints(prepare(dense));
  ASSERT_GT(d.constraints.size(), d.vertices.size());
  expect_final_within_host(cdt, d.vertices, d.constraints,
                           TileRect{kUniformX0 + 2000, kUniformX0 + 7000, kUniformY0 + 1000, kUniformY0 + 8000},
                           "more segments than points");
  InputSet grid;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) grid.points.push_back({double(i), double(j), 0.0});
  const ResolvedInput g = resolve_constraints(prepare(grid));
  expect_final_within_host(cdt, g.vertices, g.constraints, TileRect{10, 40, 5, 50}, "grid, sides on grid lines");
}

// A tile segment past the tile's points is refused, whether staged behind the points (no more segments than
// points) or uploaded in the call (more).
TEST(GpuTiles, ASegmentPastTheTilesPointsIsRefused) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  const Points all = uniform_points(100, 3).points;
  std::vector<uint32_t> ids(all.size());
  for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
  for (const size_t m : {size_t(5), size_t(150)}) {
    std::vector<Edge> segments(m, Edge{0, 1});
    segments[m - 2] = {2, 100};
    try {
      cdt.finalize_tile(TileJob{all, ids, segments, TileRect{}, "bad"});
      ADD_FAILURE() << m << " segments";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("constraint " + std::to_string(m - 2) + " has a vertex index past 100"),
                std::string::npos)
          << e.what();
    }
  }
}

// Tiles of at most tp points with the device's final test; tp = 100: slabs (a tile whose ids are a range).
TileOptions device_tiles(uint64_t tp, const gpu::GpuTiles& tiles) {
  TileOptions opt;
  opt.max_tile_points = tp;
  opt.shape = tp == 100 ? TileShape::slabs : TileShape::automatic;
  opt.finalize = tiles.finalize;
  return opt;
}

// Every hard layout in tiles of 16, 50 and 500 points, and in slabs of 100 (a tile whose ids are a range), with
// the device's final test: the single run's mesh.
TEST(GpuTiles, HardLayoutsWithTheDevicesFinalTest) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  const gpu::GpuTiles tiles = gpu::gpu_tiles({&cdt});
  for (const auto& [name, in] : tile_layouts::all()) {
    const PreparedInput p = prepare(in);
    const CdtResult single = triangulate_cgal(p);
    for (uint64_t tp : {16, 50, 500, 100}) {
      TileOptions opt = device_tiles(tp, tiles);
      if (tp == 50) opt.reserve = tiles.reserve;  // staging allocated ahead, and regrown by a later layout's tiles
      TileStats ts;
      const CdtResult tiled = triangulate_tiled(resolve_constraints(p), opt, tiles.triangulate, &ts);
      EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << name << ", tiles of " << tp;
      EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << name << ", tiles of " << tp;
      if (p.vertices.size() > tp) {
        EXPECT_GE(ts.tiles, 2u) << name << ", tiles of " << tp;
      }
    }
  }
}

// Degenerate lattice inputs (tile_layouts::lattice_soup) on every path of cdtgpu triangulate: the CPU's single
// run, its tiles (squares and slabs), the GPU's single run and its tiles as the CLI runs them (unresolved first,
// then resolved if a tile finds a crossing). One mesh: the CDT of the rules' graph. The CPU's single run was
// CGAL's own crossing handling until it crashed on the first of these.
TEST(GpuTiles, LatticeSoupsGiveOneMeshOnEveryPath) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  const gpu::GpuTiles tiles = gpu::gpu_tiles({&cdt});
  int crossing = 0;
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE("lattice soup " + std::to_string(seed));
    const PreparedInput p = prepare(tile_layouts::lattice_soup(seed));
    const CdtResult single = triangulate_cgal(p);
    // The CDT of the rules' graph: its pieces are the constrained edges.
    std::vector<Edge> constrained;
    const VerifyReport v = verify_mesh(single.mesh, p, 20, &constrained);
    EXPECT_TRUE(v.ok()) << (v.failures.empty() ? "" : v.failures.front());
    EXPECT_EQ(constrained, resolve_constraints(p).constraints);
    crossing += single.steiner_points > 0;
    auto expect_single = [&](const CdtResult& r, const std::string& what) {
      EXPECT_EQ(r.steiner_points, single.steiner_points) << what;
      EXPECT_EQ(r.mesh.vertices, single.mesh.vertices) << what;
      EXPECT_TRUE(r.mesh.triangles == single.mesh.triangles) << what;
    };
    for (const TileShape shape : {TileShape::squares, TileShape::slabs}) {
      TileOptions opt;
      opt.max_tile_points = 16;
      opt.shape = shape;
      expect_single(triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator()),
                    shape == TileShape::slabs ? "CPU slabs" : "CPU tiles");
    }
    expect_single(cdt.triangulate(p), "GPU");
    for (uint64_t tp : {40, 300}) {
      expect_single(triangulate_tiled_checking(p, device_tiles(tp, tiles), tiles.triangulate),
                    "GPU tiles of " + std::to_string(tp));
    }
  }
  EXPECT_GE(crossing, 8);
}

// Tiles of the prepared input that check themselves (core/tiles_ahead, tiled_cdt_unresolved): every hard layout
// whose resolve makes no Steiner vertex gives the single run's mesh, the segments through vertices split by the
// tiles as the resolve splits them (the same count), and every one with crossings gives up, in tiles, slabs and
// one piece alike (one piece always gives up: nothing would check it).
TEST(GpuTiles, TilesOfAnUnresolvedInputCheckThemselves) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  const gpu::GpuTiles tiles = gpu::gpu_tiles({&cdt});
  std::vector<std::pair<std::string, InputSet>> layouts = tile_layouts::all();
  auto on_grid = [](std::vector<Polyline> lines) {
    InputSet in = tile_layouts::dem_grid();
    in.lines = std::move(lines);
    return in;
  };
  using tile_layouts::line;
  // Through the grid's vertices, each a neighbour of the last.
  layouts.emplace_back("a constraint along a grid row", on_grid({line({{0, 20, 0}, {39, 20, 0}})}));
  // Chains of vertices on one segment (a pass each in a tile), across every slab and tile.
  layouts.emplace_back("a column, a diagonal and a knight's line through the grid",
                       on_grid({line({{30, 0, 0}, {30, 15, 0}}), line({{1, 1, 0}, {38, 38, 0}}),
                                line({{0, 21, 0}, {36, 39, 0}})}));
  // Footprints sharing walls, collinear overlaps of different lengths: the equal pieces merge.
  layouts.emplace_back("footprints sharing walls",
                       on_grid({line({{2, 2, 0}, {20, 2, 0}, {20, 12, 0}, {2, 12, 0}}, true),
                                line({{10, 12, 0}, {30, 12, 0}, {30, 25, 0}, {10, 25, 0}}, true),
                                line({{20, 2, 0}, {36, 2, 0}, {36, 12, 0}, {25, 12, 0}}, true)}));
  int clean = 0, through = 0, crossing = 0;
  for (const auto& [name, in] : layouts) {
    const PreparedInput p = prepare(in);
    const ResolvedInput resolved = resolve_constraints(p);
    const bool crosses = resolved.steiner_points > 0;
    (crosses ? crossing : resolved.split_at_vertices > 0 ? through : clean) += 1;
    const CdtResult single = triangulate_cgal(p);
    for (uint64_t tp : {16, 100, 500, 100000}) {
      TileStats ts;
      TileOptions opt = device_tiles(tp, tiles);
      opt.in_runs = tp == 100 || tp == 500;  // slabs' order left in the tiles' runs, then gathered; tiles' copied
      std::optional<OrderedRuns> t = tiled_cdt_unresolved(p, opt, tiles.triangulate, &ts);
      const bool one_piece = p.vertices.size() <= tp;
      EXPECT_EQ(t.has_value(), !crosses && !one_piece) << name << ", tiles of " << tp;
      if (t) {
        EXPECT_TRUE(std::move(*t).take() == single.mesh.triangles) << name << ", tiles of " << tp;
        EXPECT_EQ(ts.split_at_vertices, resolved.split_at_vertices) << name << ", tiles of " << tp;
      }
    }
  }
  EXPECT_GE(clean, 5);
  EXPECT_GE(through, 4);  // the duplicates' line too
  EXPECT_GE(crossing, 1);
  // Two segments crossing exactly at a grid vertex: the resolve splits each there (no Steiner vertex), but a tile
  // that holds both and not that vertex sees them cross, and the caller resolves.
  const PreparedInput x = prepare(on_grid({line({{10, 10, 0}, {30, 30, 0}}), line({{10, 30, 0}, {30, 10, 0}})}));
  ASSERT_EQ(resolve_constraints(x).steiner_points, 0u);
  for (uint64_t tp : {16, 100, 500})
    EXPECT_FALSE(tiled_cdt_unresolved(x, device_tiles(tp, tiles), tiles.triangulate).has_value()) << tp;
}

// A segment along a slab's cut line, through vertices that only one of the two slabs owns: that slab must get it,
// or no tile splits it at the vertices (and the merge refuses it). A 40 x 40 grid in slabs of 100 points: the
// cut at x = 2 splits that grid column, rows 0-19 left, 20-39 right. Segments found by x-range (de30fc5) failed
// this with either bound made strict.
TEST(GpuTiles, UnresolvedSlabsSeeASegmentAlongTheirCut) {
  const gpu::Context ctx = gpu::create_context(gpu::ContextOptions{});
  const gpu::GpuCdt cdt(ctx);
  const gpu::GpuTiles tiles = gpu::gpu_tiles({&cdt});
  for (const auto& [y0, y1, owner] : {std::tuple{25.0, 35.0, "right"}, std::tuple{3.0, 13.0, "left"}}) {
    InputSet in = tile_layouts::dem_grid();
    in.lines.push_back(tile_layouts::line({{2, y0, 0}, {2, y1, 0}}));
    const PreparedInput p = prepare(in);
    TileStats ts;
    std::optional<OrderedRuns> t = tiled_cdt_unresolved(p, device_tiles(100, tiles), tiles.triangulate, &ts);
    ASSERT_TRUE(t.has_value()) << "a segment through vertices of the " << owner << " slab only";
    EXPECT_TRUE(std::move(*t).take() == triangulate_cgal(p).mesh.triangles) << owner;
    EXPECT_EQ(ts.split_at_vertices, 9u) << owner;
  }
}

TEST(GpuTiles, DeviceListsAreChecked) {
  const std::vector<gpu::DeviceInfo> devices = gpu::list_devices();
  const size_t d = test_device();
  const std::vector<size_t> all = gpu::select_devices(devices, "all");
  ASSERT_FALSE(all.empty());
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  EXPECT_EQ(gpu::select_devices(devices, ""), std::vector<size_t>{d});
  EXPECT_EQ(gpu::select_devices(devices, std::to_string(d)), std::vector<size_t>{d});
  auto message = [&](const std::string& spec) {
    try {
      gpu::select_devices(devices, spec);
    } catch (const gpu::DeviceError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message(std::to_string(d) + "," + std::to_string(d)).find("twice"), std::string::npos);
  EXPECT_NE(message("first").find("device indices separated by commas"), std::string::npos);
  EXPECT_NE(message("0,,1").find("device indices separated by commas"), std::string::npos);
  EXPECT_NE(message("99").find("out of range"), std::string::npos);
}

TEST(GpuTiles, AFailingDeviceIsNamed) {
  InputSet in = uniform_points(4000, 3);
  const PreparedInput p = prepare(in);
  const size_t d = test_device();
  setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "64K", 1);  // read when a context is created
  auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  unsetenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
  TileOptions opt;
  opt.max_tile_points = 1000;
  opt.tiles_in_flight = 4;
  try {
    triangulate_tiled(resolve_constraints(p), opt, gpu::gpu_tile_triangulator({&a, &b}));
    ADD_FAILURE() << "64 KiB of device memory took a tile";
  } catch (const gpu::DeviceError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("on device " + std::to_string(d) + " ("), std::string::npos) << m;
    EXPECT_NE(m.find("vertices"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace cdtgpu
