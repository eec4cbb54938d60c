// The whole GPU backend (gpu/cdt_pipeline.hpp): prepared input -> CPU resolve -> GPU Delaunay -> GPU constraint
// insertion -> canonical mesh, against the CGAL reference backend (triangulate_cgal). Without crossing
// constraints the meshes must be identical (vertices, triangles, order); with crossings too, where the Steiner
// vertices round the same way (checked: every peer input), and verify must pass. Inputs: every peer input of
// ../shared/data/cdt-peer-inputs, the bundled Katoomba sample, the bench workloads (uniform + Delaunay edges,
// long constraints, terrain contours), random crossing segments, degenerate inputs. Validation layer on.
// CDTGPU_LARGE=1 adds 2M points + 500K constraints (the paper's headline) for the GPU machine.
#include <gtest/gtest.h>

#include "tests/peer_inputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/projection.hpp"
#include "core/verify.hpp"
#include "core/workloads.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/device_memory_pool.hpp"
#include "io/readers.hpp"
#include "gpu_test_context.hpp"

namespace cdtgpu {
namespace {

using test::ctx;
using test::no_validation_messages;

const gpu::GpuCdt& cdt() {
  static gpu::GpuCdt c(ctx());
  static const bool configured = [] {  // CDTGPU_DT_START=voronoi: ctest's gpu_pipeline_test_voronoi
    const char* start = std::getenv("CDTGPU_DT_START");
    if (start && std::string(start) == "voronoi") c.delaunay().initial_dt = gpu::DelaunayBuilder::Start::voronoi;
    return true;
  }();
  (void)configured;
  return c;
}


// GPU result equal to the reference backend's, and valid by verify. Returns the GPU stats (and the Steiner count).
gpu::GpuCdtStats expect_equal_to_cgal(const std::string& name, const InputSet& in, uint64_t* steiner = nullptr) {
  PreparedInput p = prepare(in);
  CdtResult ref = triangulate_cgal(p);
  gpu::GpuCdtStats stats;
  CdtResult got = cdt().triangulate(p, &stats);
  EXPECT_EQ(got.steiner_points, ref.steiner_points) << name;
  // The Delaunay build beside the resolve stage uses the prepared vertices, or the resolved ones when the resolve
  // is done or has found crossings first: a second build only where Steiner vertices came after the first.
  EXPECT_TRUE(!stats.delaunay_built_twice || got.mesh.vertices.size() != p.vertices.size()) << name;
  EXPECT_EQ(got.mesh.vertices.size(), ref.mesh.vertices.size()) << name;
  EXPECT_TRUE(got.mesh.vertices == ref.mesh.vertices) << name << ": vertices differ";
  EXPECT_EQ(got.mesh.triangles.size(), ref.mesh.triangles.size()) << name;
  if (got.mesh.triangles != ref.mesh.triangles) {
    size_t i = 0;
    while (i < std::min(got.mesh.triangles.size(), ref.mesh.triangles.size()) &&
           got.mesh.triangles[i] == ref.mesh.triangles[i])
      ++i;
    ADD_FAILURE() << name << ": triangles differ from CGAL's first at index " << i;
  }
  VerifyReport v = verify_mesh(got.mesh, p);
  std::string msg;
  for (const std::string& f : v.failures) msg += "  " + f + "\n";
  EXPECT_TRUE(v.ok()) << name << ":\n" << msg;
  EXPECT_EQ(v.steiner_vertices, got.steiner_points) << name;
  no_validation_messages();
  if (steiner) *steiner = ref.steiner_points;
  return stats;
}

InputSet workload(uint64_t n, uint64_t m, double f, uint64_t seed) {
  InputSet in = uniform_points(n, seed);
  add_dt_edge_constraints(in, m, f, seed);
  return in;
}

TEST(GpuPipeline, EveryPeerInput) {
  CDTGPU_SKIP_WITHOUT_PEER_INPUTS();
  const std::vector<std::filesystem::path> files = peer_input_files();
  ASSERT_GE(files.size(), 30u);
  int with_steiner = 0;  // inputs whose constraints cross: the CPU resolve stage is exercised
  for (const auto& f : files) {
    std::ifstream file(f, std::ios::binary);
    InputSet in;
    read_peer_input(file, f.string(), in);
    uint64_t steiner = 0;
    expect_equal_to_cgal(f.filename().string(), in, &steiner);
    with_steiner += steiner > 0;
  }
  EXPECT_GE(with_steiner, 5);
}

TEST(GpuPipeline, KatoombaSample) {
  const std::string dir = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  InputSet in;
  ReadOptions ro;
  ro.z_field = "ELEV";
  read_inputs({dir + "contours.shp", dir + "dem.xyz", dir + "buildings.shp"}, ro, in);
  project(in, choose_crs(in, parse_crs("auto")));
  gpu::GpuCdtStats s = expect_equal_to_cgal("katoomba", in);
  EXPECT_GT(s.gpu_total_ms, 0);
  EXPECT_GT(s.peak_device_bytes, 0u);
}

// A device memory pool's bookkeeping: best fit at the alignment asked, ranges merged with both neighbours.
TEST(DeviceMemoryPool, FreeRangesFitAlignAndMerge) {
  gpu::FreeRanges r(1000);
  EXPECT_EQ(r.take(100, 1), std::optional<uint64_t>(0));
  EXPECT_EQ(r.take(10, 64), std::optional<uint64_t>(128));  // 100..128 stays free
  EXPECT_EQ(r.take(20, 4), std::optional<uint64_t>(100));   // the gap left by the alignment, the best fit
  EXPECT_EQ(r.take(900, 1), std::nullopt);
  EXPECT_EQ(r.free_bytes(), 1000u - 130u);
  r.give(0, 100);
  r.give(128, 10);  // merged with 120..128 and 138..1000
  EXPECT_EQ(r.take(900, 1), std::nullopt) << "0..100 and 120..1000 are apart";
  r.give(100, 20);  // and now with 0..100 too
  EXPECT_EQ(r.free_bytes(), 1000u);
  EXPECT_EQ(r.take(1000, 1), std::optional<uint64_t>(0));
  // The range a buffer leaves least of, not the first that fits: 0..100 would leave 60, 110..160 leaves 10.
  gpu::FreeRanges b(1000);
  for (uint64_t n : {100, 10, 50, 10}) b.take(n, 1);
  b.give(0, 100);
  b.give(110, 50);
  EXPECT_EQ(b.fit(40, 1), std::optional<uint64_t>(10));
  EXPECT_EQ(b.take(40, 1), std::optional<uint64_t>(110));
  EXPECT_EQ(b.take(100, 1), std::optional<uint64_t>(0)) << "the exact fit";
}

// Buffers taking their memory from a pool made ahead (ContextOptions::device_pool_bytes, as `cdtgpu triangulate`
// does for inputs of 10^8 points): CGAL's bytes, every range given back once the buffers go. A pool too small
// for the run grows by blocks as its buffers need them.
TEST(GpuPipeline, BuffersFromADeviceMemoryPoolGiveTheSameResult) {
  const InputSet in = workload(20000, 5000, 0.5, 3);
  const PreparedInput p = prepare(in);
  const CdtResult ref = triangulate_cgal(p);
  for (uint64_t pool_bytes : {uint64_t(1) << 30, uint64_t(3) << 20}) {
    gpu::ContextOptions o;
    o.validation = true;
    o.device_pool_bytes = pool_bytes;
    gpu::Context c = gpu::create_context(o);
    ASSERT_TRUE(c.memory_pool.load()) << pool_bytes;
    const uint64_t made = c.memory_pool.load()->bytes();
    EXPECT_EQ(made, pool_bytes);
    {
      gpu::GpuCdt cdt(c);
      const CdtResult got = cdt.triangulate(p);
      EXPECT_TRUE(got.mesh.vertices == ref.mesh.vertices) << pool_bytes;
      EXPECT_TRUE(got.mesh.triangles == ref.mesh.triangles) << pool_bytes;
      EXPECT_GT(c.memory_pool.load()->ranges_taken(), 10u) << pool_bytes;
    }
    c.temp_pool.reset();  // the context's small scratch buffers (Recorder::temp) stay with it otherwise
    const uint64_t grown = c.memory_pool.load()->bytes();
    if (pool_bytes < (uint64_t(1) << 30))
      EXPECT_GT(grown, made) << "a pool of " << pool_bytes << " bytes is less than a 20K run takes";
    else
      EXPECT_EQ(grown, made);
    EXPECT_EQ(c.memory_pool.load()->free_bytes(), grown) << pool_bytes;
    for (const std::string& m : c.messages()) ADD_FAILURE() << m;
  }
}

TEST(GpuPipeline, BenchWorkloads) {
  expect_equal_to_cgal("uniform 20K + 5K DT edges", workload(20000, 5000, 0.5, 3));
  expect_equal_to_cgal("uniform 20K + long DT edges", workload(20000, 400, 0.02, 4));
  TerrainOptions t;
  t.grid = 120;
  t.seed = 5;
  expect_equal_to_cgal("terrain 120x120 + contours", terrain_workload(t));
}

// Random segments that cross each other many times: Steiner vertices, splits, z interpolation.
TEST(GpuPipeline, CrossingConstraints) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1000);
  InputSet in;
  in.sources = {"random crossings"};
  for (int i = 0; i < 3000; ++i) in.points.push_back({u(rng), u(rng), u(rng) / 10});
  for (int i = 0; i < 60; ++i) {
    Polyline l;
    l.points = {{u(rng), u(rng), 1}, {u(rng), u(rng), 2}};
    in.lines.push_back(l);
  }
  PreparedInput p = prepare(in);
  CdtResult ref = triangulate_cgal(p);
  ASSERT_GT(ref.steiner_points, 100u);
  expect_equal_to_cgal("random crossings", in);
}

// A grid DEM (every cell co-circular) with constraints along grid lines (through collinear vertices) and
// diagonals crossing them at vertices and between them.
TEST(GpuPipeline, GridWithConstraintsThroughVertices) {
  InputSet in;
  in.sources = {"grid"};
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) in.points.push_back({double(i), double(j), double(i + j)});
  in.lines.push_back({{{0, 10, 0}, {59, 10, 0}}});
  in.lines.push_back({{{5, 0, 0}, {5, 59, 0}}});
  in.lines.push_back({{{0, 0, 0}, {59, 59, 0}}});
  in.lines.push_back({{{0.5, 3, 0}, {40.5, 50, 0}}});
  in.lines.push_back({{{59, 0, 0}, {0, 59, 0}}});
  expect_equal_to_cgal("grid with constraints", in);
}

TEST(GpuPipeline, DegenerateInputs) {
  auto run = [](const Points& pts, const std::vector<Polyline>& lines) {
    InputSet in;
    in.points.assign(pts.begin(), pts.end());
    in.lines = lines;
    PreparedInput p = prepare(in);
    CdtResult got = cdt().triangulate(p);
    CdtResult ref = triangulate_cgal(p);
    EXPECT_EQ(got.mesh.vertices, ref.mesh.vertices);
    EXPECT_EQ(got.mesh.triangles, ref.mesh.triangles);
    return got.mesh.triangles.size();
  };
  EXPECT_EQ(run({}, {}), 0u);
  EXPECT_EQ(run({{1, 1, 1}}, {}), 0u);
  EXPECT_EQ(run({{1, 1, 1}, {2, 2, 2}}, {}), 0u);
  EXPECT_EQ(run({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {}), 1u);
  EXPECT_EQ(run({{0, 0, 0}, {1, 1, 0}, {2, 2, 0}, {3, 3, 0}}, {{{{0, 0, 0}, {3, 3, 0}}}}), 0u);  // collinear
  EXPECT_EQ(run({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}}, {{{{0, 0, 0}, {2, 2, 0}}}, {{{2, 0, 0}, {0, 2, 0}}}}),
            4u);  // two crossing diagonals: one Steiner vertex
  no_validation_messages();
}

// The canonical order sorts triangles in buckets by their smallest vertex; a vertex with a huge fan of its own
// (here the smallest vertex, at the centre of an arc of 300 points) sends the sort to the radix sort instead.
TEST(GpuPipeline, HugeFanIsSortedToo) {
  InputSet in;
  in.points.push_back({0, 0, 0});
  for (int i = 0; i < 300; ++i) {
    const double t = -1.4 + 2.8 * i / 299.0;
    in.points.push_back({std::round(1e6 * std::cos(t)) / 1e3, std::round(1e6 * std::sin(t)) / 1e3, 0});
  }
  PreparedInput p = prepare(in);
  CdtResult got = cdt().triangulate(p);
  CdtResult ref = triangulate_cgal(p);
  EXPECT_EQ(got.mesh.triangles, ref.mesh.triangles);
  size_t fan = std::count_if(ref.mesh.triangles.begin(), ref.mesh.triangles.end(),
                             [](const Triangle& t) { return t[0] == 0; });
  EXPECT_GT(fan, 64u) << "the fan must be larger than a bucket";
  no_validation_messages();
}

TEST(GpuPipeline, SameResultEveryRun) {
  PreparedInput p = prepare(workload(15000, 4000, 0.3, 9));
  CdtResult a = cdt().triangulate(p);
  CdtResult b = cdt().triangulate(p);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.vertices, b.mesh.vertices);
}

TEST(GpuPipeline, LargePaperHeadline) {
  const char* v = std::getenv("CDTGPU_LARGE");
  if (!v || std::strcmp(v, "1") != 0) GTEST_SKIP() << "set CDTGPU_LARGE=1 (GPU machine): 2M points + 500K";
  gpu::GpuCdtStats s = expect_equal_to_cgal("2M + 500K DT edges", workload(2000000, 500000, 0.5, 1));
  std::string line;
  for (const auto& [name, ms] : s.gpu_ms) line += " " + name + "=" + std::to_string(ms);
  std::printf("[ 2M+500K ] wall %.1f ms, gpu %.1f ms:%s\n", s.wall_total_ms, s.gpu_total_ms, line.c_str());
}

}  // namespace
}  // namespace cdtgpu
