// Constraint insertion on the GPU (gpu/constraints.hpp) against CGAL's constrained Delaunay triangulation, triangle
// for triangle: the Delaunay triangulation is built by CGAL on the CPU and uploaded (what the GPU Delaunay stage
// will hand over), the constraints are inserted and legalised on the GPU, and the finite triangles must equal
// triangulate_cgal(prepare(input)).mesh.triangles; the slots must pass check_triangulation and the constrained
// bits must mark exactly the constraint edges. Inputs: random points with random Delaunay edges of a subset (short
// and long constraints), contour lines over a grid DEM, building footprints among DEM points, constraints
// through collinear grid vertices (split on the CPU first), constraints that already are edges, shared
// endpoints, and the peer inputs without crossings. The validation layer is on; any message fails the test.
// CDTGPU_LARGE=1 adds the paper's headline size (2M points, 500K constraints) for the GPU machine.
#include <gtest/gtest.h>

#include "tests/peer_inputs.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/predicates.hpp"
#include "core/prepare.hpp"
#include "core/tiles.hpp"
#include "core/repair.hpp"
#include "core/workloads.hpp"
#include "gpu/canonical.hpp"
#include "gpu/check.hpp"
#include "gpu/constraints.hpp"
#include "gpu/delaunay.hpp"
#include "gpu/context.hpp"
#include "gpu/primitives.hpp"
#include "gpu/triangulation.hpp"
#include "io/readers.hpp"
#include "gpu_test_context.hpp"

namespace cdtgpu {
namespace {

using gpu::ConstraintOptions;
using gpu::ConstraintStats;

using test::ctx;
using test::no_validation_messages;

const gpu::ConstraintInserter& inserter() {
  static gpu::Primitives prims(ctx());
  static gpu::ConstraintInserter ins(ctx(), prims);
  return ins;
}

bool large() {
  const char* v = std::getenv("CDTGPU_LARGE");
  return v && std::strcmp(v, "1") == 0;
}

// CDTGPU_DT_START=voronoi (ctest's gpu_cdt_test_voronoi): every input starts from the GPU Delaunay build with
// the Voronoi first stage instead of CGAL's triangulation, so the constraint stages must give the same bytes.
bool voronoi_start() {
  const char* v = std::getenv("CDTGPU_DT_START");
  return v && std::strcmp(v, "voronoi") == 0;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// CGAL's Delaunay triangulation (perturbed, like the GPU Delaunay stage) of canonical vertices: CCW triangles.
Triangles delaunay(const Points& v) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
  using Dt = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<Vb>>;
  std::vector<std::pair<K::Point_2, uint32_t>> pts;
  pts.reserve(v.size());
  for (uint32_t i = 0; i < v.size(); ++i) pts.emplace_back(K::Point_2(v[i].x, v[i].y), i);
  Dt dt;
  dt.insert(pts.begin(), pts.end());
  Triangles out;
  if (dt.dimension() < 2) return out;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
    out.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  return out;
}

// The vertices' coordinates, two a vertex, as the triangulation's host copy holds them.
std::vector<double> xy_of(const Points& vertices) {
  std::vector<double> xy;
  xy.reserve(2 * vertices.size());
  for (const Point3& q : vertices) xy.insert(xy.end(), {q.x, q.y});
  return xy;
}

// The Delaunay triangulation the constraints start from: CGAL's, or with CDTGPU_DT_START=voronoi the GPU build
// from the Voronoi start, checked against CGAL's.
gpu::HostTriangulation start_triangulation(const std::string& name, const std::vector<double>& xy,
                                           const Points& vertices) {
  if (!voronoi_start()) return gpu::make_host_triangulation(xy, delaunay(vertices));
  gpu::DelaunayBuilder dt(ctx());
  dt.initial_dt = gpu::DelaunayBuilder::Start::voronoi;
  gpu::HostTriangulation host = gpu::download_host(ctx(), dt.build(xy));
  Triangles want = delaunay(vertices);
  for (Triangle& t : want) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(gpu::finite_triangles(host), want) << name << ": the Voronoi start's Delaunay triangulation";
  return host;
}

// Splits every constraint at the vertices lying exactly on it (vertices sorted by x, then y, as prepare makes
// them), the CPU step that precedes insertion. Pieces are returned as (smaller, larger), sorted, unique.
std::vector<Edge> split_at_vertices(const Points& v, const std::vector<Edge>& cons) {
  std::vector<Edge> out;
  auto less_x = [](const Point3& p, double x) { return p.x < x; };
  for (const Edge& e : cons) {
    const Point3 &a = v[e[0]], &b = v[e[1]];
    const double x0 = std::min(a.x, b.x), x1 = std::max(a.x, b.x), y0 = std::min(a.y, b.y), y1 = std::max(a.y, b.y);
    auto lo = std::lower_bound(v.begin(), v.end(), x0, less_x);
    std::vector<uint32_t> on = {e[0], e[1]};
    for (auto it = lo; it != v.end() && it->x <= x1; ++it) {
      uint32_t i = uint32_t(it - v.begin());
      if (i == e[0] || i == e[1] || it->y < y0 || it->y > y1) continue;
      if (pred::orient2d({a.x, a.y}, {b.x, b.y}, {it->x, it->y}) == 0) on.push_back(i);
    }
    // Canonical order is lexicographic (x, y), which is monotone along any segment.
    std::sort(on.begin(), on.end());
    for (size_t i = 0; i + 1 < on.size(); ++i) out.push_back({on[i], on[i + 1]});
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

struct Outcome {
  ConstraintStats stats;
  gpu::HostTriangulation slots;  // raw slots after insertion (for determinism checks)
};

// The whole comparison for one input; returns the GPU stats. `options` selects ablation variants; with
// gpu_runs > 1 the insertion is repeated on fresh uploads (the last run is checked and reported, all are timed).
Outcome check_against_cgal(const std::string& name, const InputSet& in, const ConstraintOptions& options = {},
                           int gpu_runs = 1) {
  Outcome out;
  auto t0 = std::chrono::steady_clock::now();
  PreparedInput p = prepare(in);
  CdtResult ref = triangulate_cgal(p);
  const double cgal_ms = ms_since(t0);
  EXPECT_EQ(ref.steiner_points, 0u) << name << ": inputs of this test must not cross";
  std::vector<Edge> cons = split_at_vertices(p.vertices, p.constraints);
  const std::vector<double> xy = xy_of(p.vertices);
  t0 = std::chrono::steady_clock::now();
  gpu::HostTriangulation host = start_triangulation(name, xy, p.vertices);
  const double dt_ms = ms_since(t0);

  const gpu::ConstraintInserter& ins = inserter();  // pipelines built before the clock starts
  gpu::GpuTriangulation tri;
  gpu::ConstrainedEdges ce;
  std::string walls;
  double gpu_ms = 0;
  for (int run = 0; run < gpu_runs; ++run) {
    tri = gpu::upload_triangulation(ctx(), host);
    t0 = std::chrono::steady_clock::now();
    ce = ins.insert(tri, cons, &out.stats, options);
    gpu_ms = ms_since(t0);
    walls += (run ? ", " : "") + std::to_string(gpu_ms);
  }

  Triangles got = gpu::download_triangles(ctx(), tri);
  out.slots = gpu::download_host(ctx(), tri);
  EXPECT_EQ(gpu::check_triangulation(out.slots), "") << name;
  EXPECT_EQ(got.size(), ref.mesh.triangles.size()) << name;
  if (got != ref.mesh.triangles) {
    size_t differ = 0;
    Triangles only_gpu;
    std::set_difference(got.begin(), got.end(), ref.mesh.triangles.begin(), ref.mesh.triangles.end(),
                        std::back_inserter(only_gpu));
    differ = only_gpu.size();
    ADD_FAILURE() << name << ": " << differ << " GPU triangles are not CGAL's, e.g. (" << only_gpu[0][0] << ", "
                  << only_gpu[0][1] << ", " << only_gpu[0][2] << ")";
  }
  EXPECT_EQ(gpu::download_constrained_edges(ctx(), tri, ce), cons) << name << ": constrained bits";
  no_validation_messages();

  const ConstraintStats& s = out.stats;
  std::cout << "[ " << name << " ] " << p.vertices.size() << " points, " << cons.size() << " constraints, "
            << s.crossed_edges << " crossed edges (at most " << s.longest_crossing << " by one); " << s.flip_rounds << " flip rounds (" << s.insertion_flips
            << " flips), " << s.legalise_rounds << " legalise rounds (" << s.legalise_flips << " flips); wall "
            << walls << " ms (CGAL CDT " << cgal_ms << " ms, CGAL DT + slots " << dt_ms << " ms); "
            << s.peak_device_bytes / 1024 << " KiB peak";
  if (s.fallback_constraints) std::cout << ", " << s.fallback_constraints << " constraints by the host safety net";
  std::cout << "\n   GPU stages:";
  for (auto& [stage, ms] : s.stage_ms) std::cout << " " << stage << " " << ms << " ms;";
  if (gpu_runs > 1) {
    std::cout << "\n   rounds (crossed/flips):";
    for (auto& r : s.rounds) std::cout << " " << r[0] << "/" << r[1];
  }
  std::cout << "\n";
  return out;
}

InputSet random_with_dt_edges(uint64_t n, uint64_t m, double f, uint64_t seed) {
  InputSet in = uniform_points(n, seed);
  add_dt_edge_constraints(in, m, f, seed + 1);
  return in;
}

Polyline line(Points pts, bool closed = false) {
  Polyline l;
  l.points = std::move(pts);
  l.closed = closed;
  return l;
}

// A square grid DEM of g x g nodes, `spacing` apart, origin (x0, y0); z a gentle slope.
void add_grid(InputSet& in, uint32_t g, double spacing, double x0 = 0, double y0 = 0) {
  if (in.sources.empty()) in.sources.push_back("grid");
  for (uint32_t j = 0; j < g; ++j)
    for (uint32_t i = 0; i < g; ++i)
      add_point(in, 0, j * g + i + 1, {x0 + i * spacing, y0 + j * spacing, 0.01 * i + 0.02 * j});
}

}  // namespace

TEST(GpuCdt, RandomDelaunayEdges) {
  check_against_cgal("random 20K, 2K DT edges f=0.1", random_with_dt_edges(20000, 2000, 0.1, 11));
}

TEST(GpuCdt, LongConstraints) {
  // f = 0.002: constraints about 25 point spacings long, crossing ~50 triangles each.
  check_against_cgal("random 30K, 150 DT edges f=0.002", random_with_dt_edges(30000, 150, 0.002, 21));
  // Edges of the Delaunay triangulation of 20 points: ~110 crossed edges each, many meeting at the same hubs.
  check_against_cgal("random 50K, 25 DT edges f=0.0004", random_with_dt_edges(50000, 25, 0.0004, 31));
}

TEST(GpuCdt, TerrainContours) {
  TerrainOptions o;
  o.grid = 120;  // 14 400 DEM nodes: every cell co-circular, the perturbation decides
  o.levels = 30;
  InputSet in = terrain_workload(o);
  check_against_cgal("terrain 120x120 + contours", in);
}

TEST(GpuCdt, BuildingFootprints) {
  // Rotated rectangles and L-shapes on a grid DEM: many small closed rings, grid nodes inside and around them.
  InputSet in;
  add_grid(in, 90, 5.0);
  std::mt19937_64 rng(7);
  uint32_t made = 0;
  for (uint32_t by = 0; by < 14; ++by)
    for (uint32_t bx = 0; bx < 14; ++bx) {
      const double cx = 16.3 + bx * 31.0 + unit_double(rng) * 3, cy = 15.7 + by * 31.0 + unit_double(rng) * 3;
      // Half-sizes below 10 x 9: rings of neighbouring cells (31 m apart) never meet.
      const double w = 4 + unit_double(rng) * 6, h = 4 + unit_double(rng) * 5, ang = unit_double(rng) * 1.5;
      const double c = std::cos(ang), s = std::sin(ang);
      auto at = [&](double u, double v) { return Point3{cx + c * u - s * v, cy + s * u + c * v, 10.0}; };
      Points ring;
      if ((bx + by) % 3 == 0)  // an L-shape
        ring = {at(-w, -h), at(w, -h), at(w, 0), at(0, 0), at(0, h), at(-w, h)};
      else
        ring = {at(-w, -h), at(w, -h), at(w, h), at(-w, h)};
      add_polyline(in, line(ring, true));
      ++made;
    }
  ASSERT_EQ(made, 196u);
  check_against_cgal("buildings 196 rings on 90x90 DEM", in);
}

TEST(GpuCdt, ConstraintsThroughCollinearVertices) {
  // Rows, columns and diagonals of a grid, crossing one another only at grid nodes: each constraint passes through
  // grid nodes and is split there on the CPU; the pieces are grid edges or cross co-circular cells' diagonals.
  InputSet in;
  add_grid(in, 60, 1.0);
  for (double y : {3.0, 17.0, 40.0}) add_polyline(in, line({{0, y, 0}, {59, y, 0}}));
  for (double x : {5.0, 33.0}) add_polyline(in, line({{x, 0, 0}, {x, 59, 0}}));
  add_polyline(in, line({{0, 0, 0}, {59, 59, 0}}));
  add_polyline(in, line({{8, 50, 0}, {32, 38, 0}}));  // slope -1/2: through every other column's node
  add_polyline(in, line({{2, 58, 0}, {26, 42, 0}}));  // slope -2/3: through every third column's node
  check_against_cgal("grid 60x60, constraints through nodes", in);
}

TEST(GpuCdt, ConstraintsAlreadyEdges) {
  // f = 1: edges of the Delaunay triangulation of all points, so nothing is crossed; only legalisation runs.
  Outcome o = check_against_cgal("random 10K, 2K edges of its own DT", random_with_dt_edges(10000, 2000, 1.0, 41));
  EXPECT_EQ(o.stats.crossed_edges, 0u);
  EXPECT_EQ(o.stats.insertion_flips, 0u);
  EXPECT_EQ(o.stats.fallback_constraints, 0u);
}

TEST(GpuCdt, SharedEndpoints) {
  // A star of 60 constraints from one vertex (left half), and a wheel: a closed ring with spokes (right half).
  InputSet in = uniform_points(8000, 51);
  std::mt19937_64 rng(52);
  Points left;
  for (const Point3& q : in.points)
    if (q.x < kUniformX0 + 5000) left.push_back(q);
  const Point3 centre = left[0];
  for (int i = 1; i <= 60; ++i) add_polyline(in, line({centre, left[1 + uniform_below(rng, left.size() - 1)]}));
  Points fan;
  for (int i = 0; i < 40; ++i) {
    double ang = i * 6.283185307179586 / 40;
    fan.push_back({kUniformX0 + 7000 + 1500 * std::cos(ang), kUniformY0 + 3000 + 1500 * std::sin(ang), 1});
  }
  add_polyline(in, line(fan, true));
  for (const Point3& q : fan) add_polyline(in, line({{kUniformX0 + 7000, kUniformY0 + 3000, 1}, q}));
  check_against_cgal("stars and a wheel on 8K points", in);
}

TEST(GpuCdt, AblationVariantsGiveTheSameTriangulation) {
  InputSet in = random_with_dt_edges(12000, 600, 0.02, 61);
  Outcome full = check_against_cgal("ablation: full method", in);
  ConstraintOptions fixed;
  fixed.layout = ConstraintOptions::Layout::FixedSlots;
  Outcome a = check_against_cgal("ablation: fixed slots", in, fixed);
  ConstraintOptions one;
  one.flipping = ConstraintOptions::Flipping::OnePerConstraint;
  Outcome b = check_against_cgal("ablation: one flip per constraint", in, one);
  ConstraintOptions claims;
  claims.domain_index = false;
  Outcome c = check_against_cgal("ablation: no influence-domain index", in, claims);
  EXPECT_EQ(c.stats.fallback_constraints, 0u);
  EXPECT_EQ(a.stats.crossed_edges, full.stats.crossed_edges);
  EXPECT_GE(b.stats.flip_rounds, full.stats.flip_rounds);
}

// Cavity insertion (a constraint crossing few edges, owning its triangles, retriangulated at once) against the
// flips alone: both CGAL's triangulation; cavities take fewer rounds and leave legalisation less to flip.
TEST(GpuCdt, CavitiesAndFlipsGiveTheSameTriangulation) {
  TerrainOptions t;
  t.grid = 100;
  t.levels = 30;
  t.seed = 73;
  for (const auto& [name, in] : {std::pair<std::string, InputSet>{"random DT edges", random_with_dt_edges(20000, 4000, 0.2, 71)},
                                 {"terrain contours", terrain_workload(t)}}) {
    Outcome with = check_against_cgal("cavities: " + name, in);
    ConstraintOptions flips_only;
    flips_only.cavities = false;
    Outcome without = check_against_cgal("flips only: " + name, in, flips_only);
    EXPECT_LT(with.stats.flip_rounds, without.stats.flip_rounds) << name;
    EXPECT_LT(with.stats.legalise_flips, without.stats.legalise_flips) << name;
  }
}

// GpuCdt shares one scratch cache between the Delaunay build, the inserter and the canonical sort, so each
// finds buffers the others filled. Here every shared buffer holds garbage before each stage: the result must be
// CGAL's all the same (every stage initialises what it reads).
TEST(GpuCdt, GarbageInTheSharedScratchChangesNothing) {
  const PreparedInput p = prepare(random_with_dt_edges(20000, 2000, 0.05, 91));
  const CdtResult ref = triangulate_cgal(p);
  const std::vector<Edge> cons = split_at_vertices(p.vertices, p.constraints);
  const std::vector<double> xy = xy_of(p.vertices);
  const uint64_t n = p.vertices.size(), slots = 2 * n + 64;  // more than a build uses
  gpu::BufferCache cache;
  auto garbage = [&](uint32_t pattern) {
    for (const char* k : gpu::kPoints4) gpu::fill(ctx(), cache.get(ctx(), k, n * 4), pattern);
    for (const char* k : gpu::kSlots4) gpu::fill(ctx(), cache.get(ctx(), k, slots * 4), pattern);
    for (const char* k : gpu::kSlots8) gpu::fill(ctx(), cache.get(ctx(), k, slots * 8), pattern);
    for (const char* k : gpu::kSlots12) gpu::fill(ctx(), cache.get(ctx(), k, slots * 12), pattern);
  };
  gpu::Primitives prims(ctx());
  gpu::DelaunayBuilder dt(ctx());
  if (voronoi_start()) dt.initial_dt = gpu::DelaunayBuilder::Start::voronoi;
  gpu::ConstraintInserter ins(ctx(), prims);
  gpu::TriangleSorter sorter(ctx(), prims);
  dt.cache = ins.cache = sorter.cache = &cache;
  garbage(0xA5A5A5A5u);
  gpu::GpuTriangulation tri = dt.build(xy);
  garbage(0x5A5A5A5Au);
  ins.insert(tri, cons);
  garbage(0xFFFFFFFFu);
  EXPECT_EQ(sorter.download(tri), ref.mesh.triangles);
  no_validation_messages();
}

TEST(GpuCdt, HostSafetyNetGivesTheSameTriangulation) {
  // Flipping stopped after one round: the host inserts the rest by retriangulating cavities, then the GPU
  // legalises every slot. Long constraints (big cavities) and a terrain (co-circular cells, collinear chains).
  ConstraintOptions net;
  net.rounds_per_submit = 1;
  net.flip_round_limit = 1;
  Outcome a = check_against_cgal("safety net: long constraints", random_with_dt_edges(30000, 150, 0.002, 21), net);
  EXPECT_GT(a.stats.fallback_constraints, 0u);
  TerrainOptions o;
  o.grid = 80;
  Outcome b = check_against_cgal("safety net: terrain", terrain_workload(o), net);
  EXPECT_GT(b.stats.fallback_constraints, 0u);
}

TEST(GpuCdt, DeterministicSlots) {
  InputSet in = random_with_dt_edges(10000, 800, 0.05, 71);
  Outcome a = check_against_cgal("determinism run 1", in);
  Outcome b = check_against_cgal("determinism run 2", in);
  EXPECT_EQ(a.slots.verts, b.slots.verts);
  EXPECT_EQ(a.slots.nbrs, b.slots.nbrs);
  EXPECT_EQ(a.stats.flip_rounds, b.stats.flip_rounds);
  EXPECT_EQ(a.stats.insertion_flips, b.stats.insertion_flips);
  EXPECT_EQ(a.stats.legalise_flips, b.stats.legalise_flips);
}

TEST(GpuCdt, ReportsBrokenRequirements) {
  // Two crossing constraints, and one through a vertex: both are refused with the constraint named.
  InputSet in;
  add_grid(in, 10, 1.0);
  PreparedInput p = prepare(in);
  const std::vector<double> xy = xy_of(p.vertices);
  gpu::HostTriangulation host = start_triangulation("broken requirements", xy, p.vertices);
  auto index = [&](double x, double y) {
    return uint32_t(std::find_if(p.vertices.begin(), p.vertices.end(),
                                 [&](const Point3& q) { return q.x == x && q.y == y; }) -
                    p.vertices.begin());
  };
  {
    gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
    std::vector<Edge> crossing = {{index(1, 2), index(4, 3)}, {index(2, 1), index(3, 4)}};
    try {
      inserter().insert(tri, crossing);
      ADD_FAILURE() << "crossing constraints were accepted";
    } catch (const gpu::DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("crosses another constraint"), std::string::npos) << e.what();
    }
  }
  {
    gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
    std::vector<Edge> through = {{index(1, 1), index(5, 3)}};  // passes through (3, 2)
    try {
      inserter().insert(tri, through);
      ADD_FAILURE() << "a constraint through a vertex was accepted";
    } catch (const gpu::DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("passes through a vertex"), std::string::npos) << e.what();
    }
  }
  // Through a neighbour of its first end (the walk turns around that end and never finds b's corner): along a
  // grid row, a column (both directions) and a diagonal of a cell.
  for (const Edge& c : {Edge{index(1, 1), index(4, 1)}, Edge{index(2, 5), index(2, 2)}, Edge{index(2, 2), index(2, 5)},
                        Edge{index(3, 3), index(5, 5)}}) {
    const Edge through = {std::min(c[0], c[1]), std::max(c[0], c[1])};
    gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
    try {
      inserter().insert(tri, {&through, 1});
      ADD_FAILURE() << "a constraint through a neighbour of its end was accepted";
    } catch (const gpu::DeviceError& e) {
      EXPECT_NE(std::string(e.what()).find("passes through a vertex"), std::string::npos) << e.what();
    }
  }
  // A tile of an unresolved input: crossing constraints are UnresolvedTile, not a device error.
  {
    gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
    gpu::ConstraintOptions o;
    o.unresolved = true;
    const std::vector<Edge> crossing = {{index(1, 2), index(4, 3)}, {index(2, 1), index(3, 4)}};
    EXPECT_THROW(inserter().insert(tri, crossing, nullptr, o), UnresolvedTile);
  }
  // And constraints through vertices are split there, a pass a vertex along each: (1, 1)-(4, 1) at (2, 1), then
  // its piece at (3, 1); (1, 1)-(5, 3) at (3, 2). Every piece is then an edge.
  {
    gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
    gpu::ConstraintOptions o;
    o.unresolved = true;
    const std::vector<Edge> through = {{index(1, 1), index(4, 1)}, {index(1, 1), index(5, 3)}};
    const gpu::ConstrainedEdges r = inserter().insert(tri, through, nullptr, o);
    std::set<std::array<uint32_t, 3>> split(r.split.begin(), r.split.end());
    const std::set<std::array<uint32_t, 3>> expected = {{index(1, 1), index(4, 1), index(2, 1)},
                                                        {index(2, 1), index(4, 1), index(3, 1)},
                                                        {index(1, 1), index(5, 3), index(3, 2)}};
    EXPECT_EQ(split, expected);
    std::vector<Edge> pieces = {{index(1, 1), index(2, 1)}, {index(2, 1), index(3, 1)}, {index(3, 1), index(4, 1)},
                                {index(1, 1), index(3, 2)}, {index(3, 2), index(5, 3)}};
    std::sort(pieces.begin(), pieces.end());
    EXPECT_EQ(gpu::download_constrained_edges(ctx(), tri, r), pieces);
    EXPECT_EQ(gpu::check_triangulation(gpu::download_host(ctx(), tri)), "");
  }
  no_validation_messages();
}

// More vertices on constraints than one pass records (CDT_THROUGH_CAP pairs): every grid row of a 100 x 100 grid
// as one constraint, 9800 vertices on them, split over several passes into the grid's 9900 unit edges.
TEST(GpuCdt, UnresolvedConstraintsSplitOverSeveralPasses) {
  InputSet in;
  add_grid(in, 100, 1.0);
  PreparedInput p = prepare(in);
  const std::vector<double> xy = xy_of(p.vertices);
  gpu::HostTriangulation host = start_triangulation("rows through a grid", xy, p.vertices);
  // prepare sorts by (x, y): the vertex at column i, row j is i * 100 + j.
  auto index = [](uint32_t i, uint32_t j) { return i * 100 + j; };
  std::vector<Edge> rows, units;
  for (uint32_t j = 0; j < 100; ++j) {
    rows.push_back({index(0, j), index(99, j)});
    for (uint32_t i = 0; i < 99; ++i) units.push_back({index(i, j), index(i + 1, j)});
  }
  std::sort(units.begin(), units.end());
  gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx(), host);
  gpu::ConstraintOptions o;
  o.unresolved = true;
  const gpu::ConstrainedEdges r = inserter().insert(tri, rows, nullptr, o);
  EXPECT_EQ(r.split.size(), 9800u);
  std::set<uint32_t> on;
  for (const auto& s : r.split) on.insert(s[2]);
  EXPECT_EQ(on.size(), 9800u);
  EXPECT_EQ(gpu::download_constrained_edges(ctx(), tri, r), units);
  EXPECT_EQ(gpu::check_triangulation(gpu::download_host(ctx(), tri)), "");
  no_validation_messages();
}

// The peer inputs of artem-ogre/CDT that need no Steiner points (crossings are another stage's job).
TEST(GpuCdt, PeerInputsWithoutCrossings) {
  CDTGPU_SKIP_WITHOUT_PEER_INPUTS();
  const std::vector<std::filesystem::path> files = peer_input_files();
  ASSERT_GE(files.size(), 30u);
  int ran = 0;
  for (const auto& f : files) {
    std::ifstream file(f, std::ios::binary);
    InputSet in;
    read_peer_input(file, f.string(), in);
    PreparedInput p = prepare(in);
    if (p.vertices.size() < 3 || triangulate_cgal(p).steiner_points > 0) continue;
    if (delaunay(p.vertices).empty()) continue;  // all collinear
    check_against_cgal(f.filename().string(), in);
    ++ran;
  }
  EXPECT_GE(ran, 15);
}

TEST(GpuCdt, LargePaperHeadline) {
  if (!large()) GTEST_SKIP() << "set CDTGPU_LARGE=1 (GPU machine): 2M points + 500K constraints";
  check_against_cgal("random 2M, 500K DT edges f=0.1", random_with_dt_edges(2000000, 500000, 0.1, 81), {}, 3);
  check_against_cgal("random 2M, 2K DT edges f=0.002", random_with_dt_edges(2000000, 2000, 0.002, 82), {}, 3);
}

TEST(GpuCdt, TriangleBuffersPassTheStorageBufferRange) {
  // The triangulation's verts and nbrs are bound by device address (shaders/tri_refs.glsl), so they may pass
  // maxStorageBufferRange: at 12 bytes per slot, 4 GiB on the H100 is ~358M slots (179M points), and lavapipe's
  // 128 MiB is 11.2M. Here a grid's triangles fill past the range, and the canonical order, which reads every
  // slot's corners and writes the sorted triples back into nbrs, must match the host's sort.
  const uint64_t range = ctx().info.max_storage_buffer_range;
  if (range > (uint64_t(512) << 20))
    GTEST_SKIP() << "range " << range << " bytes: the 256M-point bench covers it (docs/performance.md)";
  const uint64_t want = range / 12 + 50000;
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(want) / 2))) + 1;
  Triangles tris;
  tris.reserve(size_t(2) * (side - 1) * (side - 1));
  std::mt19937 rng(7);
  for (uint32_t i = 0; i + 1 < side; ++i)
    for (uint32_t j = 0; j + 1 < side; ++j) {
      const uint32_t a = i * side + j, b = a + side, c = b + 1, d = a + 1;
      tris.push_back({a, b, c});
      tris.push_back({a, c, d});
    }
  std::shuffle(tris.begin(), tris.end(), rng);
  for (Triangle& t : tris) std::rotate(t.begin(), t.begin() + rng() % 3, t.end());  // not canonical yet
  Mesh expected;
  expected.triangles = tris;
  for (uint32_t k = 0; k < side * side; ++k) expected.vertices.push_back({double(k / side), double(k % side), 0});
  canonicalize(expected);  // vertices are already in (x, y) order: ids stay

  gpu::GpuTriangulation tri;
  const uint64_t bytes = uint64_t(tris.size()) * 12;
  ASSERT_GT(bytes, range);
  tri.verts = gpu::create_addressed_buffer(ctx(), bytes, "tri_verts");
  tri.nbrs = gpu::create_addressed_buffer(ctx(), bytes, "tri_nbrs");
  gpu::upload(ctx(), tri.verts, tris.data(), bytes);
  tri.num_points = side * side;
  tri.num_slots = tri.capacity = uint32_t(tris.size());
  gpu::Primitives prims(ctx());
  gpu::TriangleSorter sorter(ctx(), prims);
  EXPECT_TRUE(sorter.download(tri) == expected.triangles);
  no_validation_messages();
}

}  // namespace cdtgpu
