// Tests of the benchmark workloads (core/workloads.hpp) and of `cdtgpu bench` run in-process.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <span>
#include <utility>

#include <nlohmann/json.hpp>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/prepare.hpp"
#include "core/verify.hpp"
#include "core/workloads.hpp"

// The bench is built into this test directly, so that the tests reach its internal functions.
#include "bench/bench.cpp"

using namespace cdtgpu;

namespace {

std::set<std::pair<double, double>> xy_set(std::span<const Point3> pts) {
  std::set<std::pair<double, double>> s;
  for (const Point3& p : pts) s.insert({p.x, p.y});
  return s;
}

// Triangulates with the reference backend and expects no Steiner points and a mesh that verify accepts.
void expect_clean_cdt(const InputSet& in) {
  PreparedInput p = prepare(in);
  ASSERT_GT(p.constraints.size(), 0u);
  CdtResult r = triangulate_cgal(p);
  EXPECT_EQ(r.steiner_points, 0u) << "constraints cross";
  EXPECT_EQ(r.mesh.vertices.size(), p.vertices.size());
  VerifyReport v = verify_mesh(r.mesh, p);
  EXPECT_TRUE(v.ok()) << (v.failures.empty() ? "" : v.failures.front());
}

}  // namespace

// Values worked out from the definitions alone: MT19937-64 (Matsumoto & Nishimura's reference algorithm, run
// in Python, which reproduces the standard's 10000th output 9981545732273789042 for the default seed) with
// seed 42, then x = (500000000 + floor(u*1e7)) / 1000 etc. with u = (r >> 11) * 2^-53, in Python floats.
TEST(Workloads, UniformPointsMatchTheDefinitionByHand) {
  InputSet in = uniform_points(3, 42);
  ASSERT_EQ(in.points.size(), 3u);
  EXPECT_EQ(in.points[0], (Point3{507551.555, 6006390.313, 75.214}));
  EXPECT_EQ(in.points[1], (Point3{501362.726, 6009032.689, 9.406}));
  EXPECT_EQ(in.points[2], (Point3{505745.703, 6003728.876, 27.387}));
  EXPECT_EQ(in.sources, std::vector<std::string>{"uniform(n=3,seed=42)"});
}

TEST(Workloads, UniformPointsAreMillimetresInsideTheSquare) {
  InputSet in = uniform_points(5000, 7);
  for (const Point3& p : in.points) {
    ASSERT_GE(p.x, kUniformX0);
    ASSERT_LT(p.x, kUniformX0 + kUniformSide);
    ASSERT_GE(p.y, kUniformY0);
    ASSERT_LT(p.y, kUniformY0 + kUniformSide);
    ASSERT_EQ(std::llround(p.x * 1000) / 1000.0, p.x);
    ASSERT_EQ(std::llround(p.y * 1000) / 1000.0, p.y);
  }
}

TEST(Workloads, UniformBelowStaysInRangeAndCoversIt) {
  std::mt19937_64 rng(3);
  std::vector<int> seen(7, 0);
  for (int i = 0; i < 700; ++i) {
    uint64_t v = uniform_below(rng, 7);
    ASSERT_LT(v, 7u);
    ++seen[v];
  }
  for (int c : seen) EXPECT_GT(c, 50);
}

TEST(Workloads, SameSeedSameInputDifferentSeedDifferentInput) {
  auto make = [](uint64_t seed) {
    InputSet in = uniform_points(4000, seed);
    add_dt_edge_constraints(in, 1500, 0.5, seed);
    return in;
  };
  uint64_t a = checksum(make(11)), b = checksum(make(11)), c = checksum(make(12));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  TerrainOptions t;
  t.grid = 50;
  t.seed = 5;
  uint64_t ta = checksum(terrain_workload(t)), tb = checksum(terrain_workload(t));
  t.seed = 6;
  EXPECT_EQ(ta, tb);
  EXPECT_NE(ta, checksum(terrain_workload(t)));
}

TEST(Workloads, DelaunayEdgeConstraintsEndOnInputPointsAndNeverCross) {
  for (double f : {0.5, 0.05}) {
    InputSet in = uniform_points(3000, 21);
    uint64_t m = f == 0.5 ? 1500 : 150;
    add_dt_edge_constraints(in, m, f, 21);
    ASSERT_EQ(in.lines.size(), m);
    ASSERT_EQ(in.sources.size(), 2u);
    auto pts = xy_set(in.points);
    std::set<std::pair<std::pair<double, double>, std::pair<double, double>>> distinct;
    for (const Polyline& l : in.lines) {
      ASSERT_EQ(l.points.size(), 2u);
      EXPECT_FALSE(l.closed);
      EXPECT_EQ(l.source, 1u);
      for (const Point3& q : l.points) EXPECT_TRUE(pts.count({q.x, q.y}));
      auto a = std::make_pair(l.points[0].x, l.points[0].y), b = std::make_pair(l.points[1].x, l.points[1].y);
      distinct.insert({std::min(a, b), std::max(a, b)});
    }
    EXPECT_EQ(distinct.size(), m) << "edges are sampled without repetition";
    expect_clean_cdt(in);
  }
}

TEST(Workloads, SmallerFractionGivesLongerConstraints) {
  auto mean_len = [](double f) {
    InputSet in = uniform_points(4000, 2);
    add_dt_edge_constraints(in, 200, f, 2);
    double s = 0;
    for (const Polyline& l : in.lines)
      s += std::hypot(l.points[1].x - l.points[0].x, l.points[1].y - l.points[0].y);
    return s / 200;
  };
  // Expected ratio sqrt(0.5 / 0.05) = 3.2.
  EXPECT_GT(mean_len(0.05), 2.5 * mean_len(0.5));
}

TEST(Workloads, TooManyConstraintsIsAUsageError) {
  InputSet in = uniform_points(100, 1);
  EXPECT_THROW(add_dt_edge_constraints(in, 1000, 0.5, 1), UsageError);
  EXPECT_THROW(add_dt_edge_constraints(in, 10, 0, 1), UsageError);
}

TEST(Workloads, TerrainContoursNeverCrossAndAvoidDemNodes) {
  for (uint64_t seed : {1, 2, 3}) {
    TerrainOptions t;
    // Rough terrain and many levels, so that about 50 saddle cells per seed are crossed by a contour (the
    // default terrain is smooth and has almost none).
    t.grid = 70;
    t.hills = 60;
    t.sigma_min = 0.03;
    t.sigma_max = 0.06;
    t.levels = 150;
    t.seed = seed;
    InputSet in = terrain_workload(t);
    ASSERT_EQ(in.points.size(), 70u * 70u);
    ASSERT_GT(in.lines.size(), 5u);
    auto dem = xy_set(in.points);
    std::set<double> levels;
    for (const Polyline& l : in.lines) {
      EXPECT_EQ(l.source, 1u);
      levels.insert(l.points[0].z);
      for (const Point3& q : l.points) {
        EXPECT_FALSE(dem.count({q.x, q.y})) << "contour vertex on a DEM node";
        EXPECT_EQ(q.z, l.points[0].z) << "a contour keeps its level";
        EXPECT_GT(q.x, kUniformX0);
        EXPECT_LT(q.x, kUniformX0 + 690);
      }
    }
    EXPECT_GT(levels.size(), 120u);
    expect_clean_cdt(in);
  }
}

TEST(Workloads, TerrainDemFollowsTheHills) {
  TerrainOptions t;
  t.grid = 40;
  t.seed = 9;
  Terrain hills = make_terrain(t);
  InputSet in = terrain_workload(t);
  const Point3& p = in.points[41];  // node (1, 1)
  EXPECT_EQ(p.x, kUniformX0 + 10);
  EXPECT_EQ(p.y, kUniformY0 + 10);
  EXPECT_NEAR(p.z, hills(10, 10), 0.0005);
  // Sum of Gaussians evaluated directly with std::exp.
  double h = 0;
  for (size_t k = 0; k < hills.cx.size(); ++k)
    h += hills.height[k] * std::exp(-((10 - hills.cx[k]) * (10 - hills.cx[k]) + (10 - hills.cy[k]) * (10 - hills.cy[k])) /
                                    (2 * hills.sigma[k] * hills.sigma[k]));
  EXPECT_NEAR(hills(10, 10), h, 1e-9);
}

TEST(Workloads, FastCgalEqualsReferenceBackend) {
  InputSet in = uniform_points(5000, 4);
  add_dt_edge_constraints(in, 500, 0.05, 4);
  PreparedInput p = prepare(in);
  BackendRun fast = run_cgal_fast(p);
  canonicalize(fast.mesh);
  CdtResult ref = triangulate_cgal(p);
  EXPECT_EQ(fast.mesh.vertices, ref.mesh.vertices);
  EXPECT_EQ(fast.mesh.triangles, ref.mesh.triangles);
  EXPECT_GT(fast.total_ms, 0);
}

TEST(Bench, QuickRunEndToEnd) {
  auto json_path = std::filesystem::temp_directory_path() / "cdtgpu_workloads_test_bench.json";
  std::filesystem::remove(json_path);
  BenchOptions o;
  o.table = "all";
  o.sizes = {"3K"};
  o.runs = 1;
  o.json_path = json_path.string();
  ASSERT_EQ(run_bench(o), 0);
  std::ifstream f(json_path);
  nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["rows"].size(), 1u + 5u + 1u + 1u);  // table 1, table 2, long, terrain
  for (const auto& row : j["rows"]) {
    EXPECT_TRUE(row["check"]["cgal_equal"].get<bool>()) << row["table"];
    EXPECT_EQ(row["cgal"]["runs_ms"].size(), 1u);
    // The GPU backend ran too, and gave CGAL's triangles.
    EXPECT_TRUE(row["check"]["gpu_equal"].get<bool>()) << row["table"];
    EXPECT_EQ(row["gpu"]["runs_ms"].size(), 1u);
    EXPECT_GT(row["gpu"]["device_median_ms"].get<double>(), 0);
    EXPECT_GT(row["gpu"]["peak_device_bytes"].get<uint64_t>(), 0u);
    EXPECT_TRUE(row["gpu"]["stage_median_ms"].contains("dt flip"));
    EXPECT_TRUE(row["gpu"]["stage_median_ms"].contains("cdt legalise"));
    EXPECT_GT(row["triangles"].get<uint64_t>(), 0u);
  }
  EXPECT_EQ(j["rows"][1]["points"], 6000);       // table 2: twice the smallest size
  EXPECT_EQ(j["rows"][5]["sources"][1], "dt-edges(m=3000,f=0.5,seed=1)");  // with 50% as many constraints
  std::filesystem::remove(json_path);
}

TEST(Bench, AblationVariantsAllGiveCgalsTriangles) {
  auto json_path = std::filesystem::temp_directory_path() / "cdtgpu_workloads_test_ablation.json";
  BenchOptions o;
  o.ablation = true;
  o.sizes = {"4K"};
  o.runs = 1;
  o.json_path = json_path.string();
  ASSERT_EQ(run_bench(o), 0);
  std::ifstream f(json_path);
  nlohmann::json j = nlohmann::json::parse(f);
  ASSERT_EQ(j["workloads"].size(), 3u);  // a tenth, a quarter and half as many constraints as points
  EXPECT_EQ(j["workloads"][0]["constraints"], 400);
  EXPECT_EQ(j["workloads"][1]["constraints"], 1000);
  EXPECT_EQ(j["workloads"][2]["constraints"], 2000);
  for (const auto& w : j["workloads"]) {
    // full, fixed slots, one flip per constraint, no domain index, flips only, the Voronoi first stage
    ASSERT_EQ(w["variants"].size(), 6u);
    for (const auto& v : w["variants"]) EXPECT_TRUE(v["cgal_equal"].get<bool>()) << v["variant"];
    EXPECT_EQ(w["variants"][3]["variant"], "no influence-domain index (slot claims alone)");
    EXPECT_NE(w["variants"][5]["variant"].get<std::string>().find("Voronoi"), std::string::npos);
  }
  std::filesystem::remove(json_path);
}

TEST(Bench, CgalOnlyLeavesTheGpuColumnsEmpty) {
  auto json_path = std::filesystem::temp_directory_path() / "cdtgpu_workloads_test_cgal_only.json";
  BenchOptions o;
  o.table = "1";
  o.sizes = {"2K"};
  o.runs = 1;
  o.gpu = false;
  o.json_path = json_path.string();
  ASSERT_EQ(run_bench(o), 0);
  std::ifstream f(json_path);
  nlohmann::json j = nlohmann::json::parse(f);
  ASSERT_EQ(j["rows"].size(), 1u);
  EXPECT_TRUE(j["rows"][0]["gpu"].is_null());
  std::filesystem::remove(json_path);
}

TEST(Bench, BadSizeIsAUsageError) {
  BenchOptions o;
  o.gpu = false;
  o.sizes = {"12Q"};
  EXPECT_THROW(run_bench(o), UsageError);
}
