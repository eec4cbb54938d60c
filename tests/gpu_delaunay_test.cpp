// gpu/delaunay against CGAL's Delaunay_triangulation_2 (Epick): the same finite triangles, in canonical
// order, and a valid closed triangulation (check_triangulation), on uniform, clustered, grid (all
// co-circular), lines, integer-with-duplicates, UTM-scale and collinear-hull inputs and 300 small degenerate
// ones; the degenerate inputs (0..3 points, all collinear) give no triangles; two runs give the same slots.
// CI sizes are tens of thousands of points. Environment:
//   CDTGPU_LARGE=1             adds 1M and 4M uniform points and a 2000 x 1000 grid (for the GPU machine)
//   CDTGPU_DT_BENCH=N          times N builds of CDTGPU_DT_BENCH_POINTS (default 2M) uniform points
//                              (CDTGPU_DT_BENCH_GRID=1: a grid 2000 wide) and prints median GPU ms per stage
//   CDTGPU_DT_PROFILE_KERNELS=1  per kernel too, per round and per flip-list length
//   CDTGPU_DT_FLIP_BATCH=K     DelaunayBuilder::flip_passes_per_submit
//   CDTGPU_DT_TAIL=0|1         DelaunayBuilder::tail_passes
//   CDTGPU_DT_SMALL=0|1        DelaunayBuilder::small_rounds
//   CDTGPU_DT_EXACT=separate|inline|adaptive  DelaunayBuilder::exact_checks
//   CDTGPU_DT_SAMPLE=S         DelaunayBuilder::sample_stride (1: no sampled rounds)
//   CDTGPU_DT_START=voronoi    DelaunayBuilder::initial_dt in every test (ctest runs the suite so as well)
//   CDTGPU_DT_SMALL_CASES=N    small degenerate cases (default 300)
//   CDTGPU_VALIDATION=0        validation off (it is on by default, and a missing layer is then an error)
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "gpu/context.hpp"
#include "gpu/delaunay.hpp"
#include "gpu/triangulation.hpp"

using namespace cdtgpu;
using namespace cdtgpu::gpu;

namespace {

bool env_is(const char* name, const char* value) {
  const char* v = std::getenv(name);
  return v && std::strcmp(v, value) == 0;
}

Context& ctx() {
  static Context c = [] {
    // Validation on by default, and a missing layer is then an error; CDTGPU_VALIDATION=0 turns it off
    // (timing, or a machine without the layer).
    setenv("CDTGPU_VALIDATION", "1", 0);
    ContextOptions options;
    options.validation = std::strcmp(std::getenv("CDTGPU_VALIDATION"), "0") != 0;
    return create_context(options);
  }();
  return c;
}

bool voronoi_start() { return env_is("CDTGPU_DT_START", "voronoi"); }

// A builder with the start CDTGPU_DT_START asks for.
DelaunayBuilder new_builder() {
  DelaunayBuilder d(ctx());
  if (voronoi_start()) d.initial_dt = DelaunayBuilder::Start::voronoi;
  return d;
}

DelaunayBuilder& builder() {
  static DelaunayBuilder b = [] {
    DelaunayBuilder d = new_builder();
    if (const char* k = std::getenv("CDTGPU_DT_FLIP_BATCH"))
      d.flip_passes_per_submit = uint32_t(std::atoi(k));
    d.profile_kernels = env_is("CDTGPU_DT_PROFILE_KERNELS", "1");
    if (const char* t = std::getenv("CDTGPU_DT_TAIL")) d.tail_passes = std::strcmp(t, "1") == 0;
    if (const char* t = std::getenv("CDTGPU_DT_SMALL")) d.small_rounds = std::strcmp(t, "1") == 0;
    if (const char* k = std::getenv("CDTGPU_DT_SAMPLE")) d.sample_stride = uint32_t(std::atoi(k));
    if (const char* k = std::getenv("CDTGPU_DT_SAMPLE_UNTIL")) d.sample_until = uint32_t(std::atoi(k));
    if (const char* e = std::getenv("CDTGPU_DT_EXACT")) {
      using E = DelaunayBuilder::ExactChecks;
      d.exact_checks = std::strcmp(e, "inline") == 0     ? E::inlined
                       : std::strcmp(e, "separate") == 0 ? E::separate
                                                         : E::adaptive;
    }
    return d;
  }();
  return b;
}

bool large() { return env_is("CDTGPU_LARGE", "1"); }

void no_validation_messages() {
  for (auto& m : ctx().messages()) ADD_FAILURE() << m;
  ctx().clear_messages();
}

struct Rng {
  explicit Rng(uint64_t seed) : g(seed) {}
  double unit() { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  double normal() {  // Box-Muller, written out so the numbers do not depend on the library
    double u = unit(), v = unit();
    return std::sqrt(-2.0 * std::log(1.0 - u)) * std::cos(6.283185307179586 * v);
  }
  std::mt19937_64 g;
};

// Canonical order, as core/prepare: sorted by (x, y), exact duplicates merged.
std::vector<double> canonical(std::vector<std::pair<double, double>> pts) {
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  std::vector<double> xy;
  xy.reserve(pts.size() * 2);
  for (auto& [x, y] : pts) {
    xy.push_back(x);
    xy.push_back(y);
  }
  return xy;
}

Triangles cgal_delaunay(const std::vector<double>& xy) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb>;
  using Dt = CGAL::Delaunay_triangulation_2<K, Tds>;
  std::vector<std::pair<K::Point_2, uint32_t>> pts;
  pts.reserve(xy.size() / 2);
  for (uint32_t i = 0; i < xy.size() / 2; ++i) pts.push_back({K::Point_2(xy[2 * i], xy[2 * i + 1]), i});
  Dt dt;
  dt.insert(pts.begin(), pts.end());
  Triangles out;
  if (dt.dimension() < 2) return out;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f) {
    Triangle t{f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Builds on the GPU, checks the slots and compares with CGAL.
DelaunayStats expect_cgal(const std::string& name, const std::vector<double>& xy,
                          const DelaunayBuilder& dt = builder()) {
  const size_t n = xy.size() / 2;
  DelaunayStats stats;
  auto t0 = std::chrono::steady_clock::now();
  GpuTriangulation tri = dt.build(xy, &stats);
  const double gpu_ms = ms_since(t0);
  HostTriangulation host = download_host(ctx(), tri);
  Triangles got = finite_triangles(host);
  t0 = std::chrono::steady_clock::now();
  Triangles want = cgal_delaunay(xy);
  const double cgal_ms = ms_since(t0);
  std::string stages;
  for (auto& [stage, ms] : stats.stage_ms)
    stages.append(" ").append(stage).append("=").append(std::to_string(ms).substr(0, 7));
  if (stats.voronoi.used) {
    const VoronoiStats& v = stats.voronoi;
    std::printf("[ vd ] %-22s grid=%ux%u sites=%u kept=%u lost=%u repairs=%u demoted=%u full=%u fallback=%d "
                "flips=%llu\n",
                name.c_str(), v.grid_width, v.grid_height, v.sites, v.kept, v.lost, v.repairs, v.demoted,
                v.full_floods, int(v.fallback), (unsigned long long)v.flips);
  }
  std::printf(
      "[ dt ] %-22s n=%zu triangles=%zu rounds=%u flip_passes=%u flips=%llu exact walks/checks=%llu/%llu "
      "bytes/pt=%.1f build=%.0f ms (gpu:%s) cgal=%.0f ms\n",
      name.c_str(), n, got.size(), stats.rounds, stats.flip_passes, (unsigned long long)stats.flips,
      (unsigned long long)stats.exact_walks, (unsigned long long)stats.exact_checks,
      n ? double(stats.peak_device_bytes) / double(n) : 0.0, gpu_ms, stages.c_str(), cgal_ms);
  EXPECT_EQ(check_triangulation(host), "") << name;
  // The per-round log adds up: every point but the first triangle's inserted once, every flip counted once.
  EXPECT_EQ(stats.round_log.size(), stats.rounds) << name;
  uint64_t inserted = 0, flips = 0;
  for (const DelaunayStats::Round& r : stats.round_log) {
    inserted += r.inserted;
    flips += r.flips;
  }
  if (stats.rounds > 0) {
    EXPECT_EQ(inserted, n - stats.start_vertices) << name;
  }
  EXPECT_EQ(flips + stats.voronoi.flips, stats.flips) << name;
  EXPECT_EQ(got.size(), want.size()) << name;
  if (got.size() != want.size()) return stats;
  size_t diff = 0;
  for (size_t i = 0; i < got.size(); ++i)
    if (got[i] != want[i] && diff++ < 3)
      ADD_FAILURE() << name << ": triangle " << i << " is (" << got[i][0] << "," << got[i][1] << ","
                    << got[i][2] << "), CGAL has (" << want[i][0] << "," << want[i][1] << "," << want[i][2]
                    << ")";
  EXPECT_EQ(diff, 0u) << name;
  no_validation_messages();
  return stats;
}

std::vector<double> uniform(size_t n, uint64_t seed) {
  Rng r(seed);
  std::vector<std::pair<double, double>> pts(n);
  for (auto& p : pts) p = {r.unit(), r.unit()};
  return canonical(pts);
}

std::vector<double> grid(uint32_t nx, uint32_t ny, double x0, double y0, double step) {
  std::vector<std::pair<double, double>> pts;
  for (uint32_t i = 0; i < nx; ++i)
    for (uint32_t j = 0; j < ny; ++j) pts.push_back({x0 + i * step, y0 + j * step});
  return canonical(pts);
}

}  // namespace

TEST(GpuDelaunay, UniformMatchesCgal) {
  if (!env_is("CDTGPU_VALIDATION", "0")) {
    EXPECT_TRUE(ctx().validation);
  }
  expect_cgal("uniform 20k", uniform(20000, 1));
  expect_cgal("uniform 1k", uniform(1000, 2));
}

// Gaussian blobs (per_blob points each) far denser than a uniform background of 3000 points in the unit
// square.
std::vector<double> clustered(uint64_t seed, int count, int per_blob) {
  Rng r(seed);
  std::vector<std::pair<double, double>> pts;
  for (int b = 0; b < count; ++b) {
    double cx = r.uniform(0.1, 0.9), cy = r.uniform(0.1, 0.9), s = r.uniform(0.005, 0.02);
    for (int i = 0; i < per_blob; ++i) pts.push_back({cx + s * r.normal(), cy + s * r.normal()});
  }
  for (int i = 0; i < 3000; ++i) pts.push_back({r.unit(), r.unit()});
  return canonical(pts);
}

TEST(GpuDelaunay, ClusteredMatchesCgal) {
  expect_cgal("clustered", clustered(3, 6, 2000));  // blobs 100x denser than the background
}

TEST(GpuDelaunay, GridDemAllCocircular) {
  expect_cgal("grid 150x100", grid(150, 100, 0, 0, 1));
  expect_cgal("grid 7x5 utm", grid(7, 5, 500000.25, 6000000.5, 10));
}

TEST(GpuDelaunay, PointsOnLines) {
  Rng r(4);
  std::vector<std::pair<double, double>> pts;
  for (int l = 0; l < 5; ++l) {  // lines through random points with random rational-ish slopes, exact steps
    double x0 = std::floor(r.uniform(0, 1000)), y0 = std::floor(r.uniform(0, 1000));
    double dx = std::floor(r.uniform(-8, 9)), dy = std::floor(r.uniform(-8, 9));
    if (dx == 0 && dy == 0) dx = 1;
    for (int i = 0; i < 1500; ++i) pts.push_back({x0 + i * dx, y0 + i * dy});
  }
  for (int i = 0; i < 1000; ++i)
    pts.push_back({std::floor(r.uniform(-5000, 5000)), std::floor(r.uniform(-5000, 5000))});
  expect_cgal("lines", canonical(pts));
}

// 30000 draws from the 150 x 120 integer lattice (about 14600 distinct points), merged.
std::vector<double> integer_lattice(uint64_t seed) {
  Rng r(seed);
  std::vector<std::pair<double, double>> pts;
  for (int i = 0; i < 30000; ++i)
    pts.push_back({std::floor(r.uniform(0, 150)), std::floor(r.uniform(0, 120))});
  return canonical(pts);
}

TEST(GpuDelaunay, IntegerCoordinatesWithDuplicates) {
  std::vector<double> xy = integer_lattice(5);
  EXPECT_LT(xy.size() / 2, 30000u);
  expect_cgal("integers+duplicates", xy);
}

TEST(GpuDelaunay, UtmScaleMillimetres) {
  Rng r(6);
  std::vector<std::pair<double, double>> pts;
  for (int i = 0; i < 20000; ++i)
    pts.push_back(
        {std::floor(500000000.0 + r.unit() * 2e6) / 1000, std::floor(6000000000.0 + r.unit() * 2e6) / 1000});
  expect_cgal("utm mm", canonical(pts));
}

TEST(GpuDelaunay, HullWithManyCollinearPoints) {
  // A grid's border (400 collinear points per side) around random inside points.
  Rng r(7);
  std::vector<std::pair<double, double>> pts;
  for (int i = 0; i <= 400; ++i) {
    pts.push_back({double(i), 0});
    pts.push_back({double(i), 400});
    pts.push_back({0, double(i)});
    pts.push_back({400, double(i)});
  }
  for (int i = 0; i < 5000; ++i) pts.push_back({r.uniform(1, 399), r.uniform(1, 399)});
  expect_cgal("collinear hull", canonical(pts));
  expect_cgal("border only",
              canonical(std::vector<std::pair<double, double>>(pts.begin(), pts.begin() + 1604)));
}

TEST(GpuDelaunay, DegenerateInputsGiveNoTriangles) {
  for (size_t n : {0u, 1u, 2u}) {
    std::vector<double> xy;
    for (size_t i = 0; i < n; ++i) xy.insert(xy.end(), {double(i), 2.0 * i});
    GpuTriangulation tri = builder().build(xy);
    EXPECT_EQ(tri.num_slots, 0u) << n;
    EXPECT_EQ(tri.num_points, n);
  }
  std::vector<std::pair<double, double>> line;
  for (int i = 0; i < 5000; ++i)
    line.push_back({500000.0 + 0.001 * i, 6000000.0 + 0.003 * i});  // rounded: near
  expect_cgal("near-collinear utm", canonical(line));               // not collinear after rounding: slivers
  std::vector<std::pair<double, double>> exact;
  for (int i = 0; i < 5000; ++i) exact.push_back({3.0 * i, -7.0 * i + 11});
  GpuTriangulation collinear = builder().build(canonical(exact));
  EXPECT_EQ(collinear.num_slots, 0u);
  expect_cgal("three points", {0, 0, 1, 5, 2, 1});
  expect_cgal("three points cw", {0, 0, 1, -5, 2, 1});
  expect_cgal("collinear + one", canonical([] {
                std::vector<std::pair<double, double>> p;
                for (int i = 0; i < 2000; ++i) p.push_back({double(i), double(i)});
                p.push_back({1000, 0});
                return p;
              }()));
  no_validation_messages();
}

TEST(GpuDelaunay, ManySmallDegenerateInputs) {
  // Small point sets on tiny integer lattices (collinear and co-circular everywhere), lattices moved to UTM
  // magnitudes, and lattice points nudged by an ulp: every round, flip and walk corner case, many times over.
  const char* cases = std::getenv("CDTGPU_DT_SMALL_CASES");  // more for a soak run
  const int count = cases ? std::atoi(cases) : 300;
  Rng r(9);
  int compared = 0;
  for (int it = 0; it < count; ++it) {
    const int n = 3 + int(r.g() % (it % 10 == 9 ? 400 : 60)), side = 2 + int(r.g() % (it % 10 == 9 ? 30 : 7));
    const int style = int(r.g() % 3);
    std::vector<std::pair<double, double>> pts;
    for (int i = 0; i < n; ++i) {
      double x = double(r.g() % side), y = double(r.g() % side);
      if (style == 1) x = 500000.0 + 0.125 * x, y = 6000000.0 + 0.125 * y;
      // An ulp off the lattice; not at 0, whose neighbours are denormals, outside the predicates' range.
      if (style == 2 && (r.g() & 7) == 0 && x != 0) x = std::nextafter(x, r.g() & 1 ? HUGE_VAL : -HUGE_VAL);
      pts.push_back({x, y});
    }
    std::vector<double> xy = canonical(pts);
    HostTriangulation host = download_host(ctx(), builder().build(xy));
    Triangles want = cgal_delaunay(xy);
    if (!host.verts.empty()) {
      ASSERT_EQ(check_triangulation(host), "") << "case " << it;
    }
    ASSERT_EQ(finite_triangles(host), want) << "case " << it << ", " << xy.size() / 2 << " points";
    compared += !want.empty();
  }
  EXPECT_GT(compared, count * 2 / 3);
  no_validation_messages();
}

// Two builds of the same points give the same slots, neighbours included.
void expect_same_slots_twice(const DelaunayBuilder& dt, const std::vector<double>& xy) {
  HostTriangulation a = download_host(ctx(), dt.build(xy));
  HostTriangulation b = download_host(ctx(), dt.build(xy));
  EXPECT_EQ(a.verts, b.verts);
  EXPECT_EQ(a.nbrs, b.nbrs);
  no_validation_messages();
}

TEST(GpuDelaunay, SameSlotsOnEveryRun) { expect_same_slots_twice(builder(), uniform(15000, 8)); }

// The flip kernel whose last workgroup runs the short passes itself (the GPU default; forced here so that
// lavapipe runs it too): the same triangles, the tail must have run, and the same slots on every run.
TEST(GpuDelaunay, TailPassesMatchCgal) {
  DelaunayBuilder dt = new_builder();
  dt.tail_passes = true;
  uint32_t tail = 0;
  tail += expect_cgal("tail: uniform 20k", uniform(20000, 21), dt).tail_passes;
  tail += expect_cgal("tail: grid 120x90", grid(120, 90, 0, 0, 1), dt).tail_passes;
  tail += expect_cgal(
              "tail: collinear hull + inside",
              [] {
                std::vector<std::pair<double, double>> pts;
                for (int i = 0; i <= 400; ++i) pts.push_back({i * 0.25, 0.0});
                Rng r(22);
                for (int i = 0; i < 2000; ++i) pts.push_back({r.uniform(0, 100), r.uniform(0, 3)});
                return canonical(pts);
              }(),
              dt)
              .tail_passes;
  EXPECT_GT(tail, 0u);
  expect_same_slots_twice(dt, uniform(15000, 23));
}

// The first rounds over a sample of the points (every 8th or 32nd listed), then every point from a sample
// point's slot: the same triangles on uniform, clustered, grid and duplicate-heavy input, and the same slots
// on every run.
TEST(GpuDelaunay, SampledRoundsMatchCgal) {
  const std::pair<std::string, std::vector<double>> inputs[] = {
      {"uniform 20k", uniform(20000, 42)},
      {"clustered", clustered(41, 4, 3000)},
      {"grid 150x100", grid(150, 100, 500000, 6000000, 1)},
      {"integers+dups", integer_lattice(41)}};
  for (uint32_t stride : {8u, 32u}) {
    DelaunayBuilder dt = new_builder();
    dt.sample_stride = stride;
    dt.sample_min_points = 0;
    dt.sample_until = stride == 8 ? 8 : 2;  // the default, and longer sampling
    for (const auto& [name, xy] : inputs) {
      const std::string label = "sampled: " + name + " /" + std::to_string(stride);
      const uint32_t sampled = expect_cgal(label, xy, dt).sampled_rounds;
      if (!voronoi_start()) {
        EXPECT_GE(sampled, 3u) << label;
      }
    }
    expect_same_slots_twice(dt, uniform(15000, 43));
  }
}

// The first rounds' insertion steps in one workgroup (dt_insert_small) or dispatched one by one: the same
// triangles either way, on inputs whose every round is small (a few hundred points) and on larger ones, where
// the build switches from the one to the other; and the same slots on every run.
TEST(GpuDelaunay, SmallRoundsMatchCgal) {
  const std::pair<std::string, std::vector<double>> inputs[] = {
      {"uniform 300", uniform(300, 51)},
      {"uniform 20k", uniform(20000, 52)},
      {"grid 40x30", grid(40, 30, 500000, 6000000, 1)},
      {"integers+dups", integer_lattice(53)},
      {"clustered", clustered(54, 4, 1500)}};
  for (bool small : {false, true}) {
    DelaunayBuilder dt = new_builder();
    dt.small_rounds = small;
    for (const auto& [name, xy] : inputs) {
      const std::string label = std::string(small ? "small rounds: " : "dispatched rounds: ") + name;
      const DelaunayStats stats = expect_cgal(label, xy, dt);
      if (small && !voronoi_start()) {
        EXPECT_GE(stats.small_rounds, 3u) << label;
      } else if (!small) {
        EXPECT_EQ(stats.small_rounds, 0u) << label;
      }
    }
    expect_same_slots_twice(dt, uniform(5000, 55));
  }
}

// Most points outside the first triangle and many on the final hull: outside insertions every round.
TEST(GpuDelaunay, RingAndAnnulus) {
  for (int seed = 0; seed < 2; ++seed) {
    Rng r(100 + seed);
    std::vector<std::pair<double, double>> ring, annulus;
    for (int i = 0; i < 3000; ++i) {
      double a = r.uniform(0, 6.283185307179586), d = 1 + r.uniform(0, 1e-3);
      ring.push_back({d * std::cos(a), d * std::sin(a)});
      double d2 = 1 + r.uniform(0, 0.2);
      annulus.push_back({d2 * std::cos(a) * 3, d2 * std::sin(a)});
    }
    expect_cgal("ring " + std::to_string(seed), canonical(ring));
    expect_cgal("annulus " + std::to_string(seed), canonical(annulus));
  }
}

// The kernel log of one profiled build: in recording order, and its flip checks' list lengths account for
// every dispatched pass that had a list (flip_passes counts the lists, tail_passes those run in a tail).
void expect_kernel_log(const DelaunayStats& stats) {
  ASSERT_FALSE(stats.kernel_log.empty());
  uint32_t checks = 0, nonempty = 0, last_round = 0;
  for (const auto& k : stats.kernel_log) {
    EXPECT_GE(k.ms, 0.0) << k.name;
    EXPECT_GE(k.round, last_round) << k.name;  // in recording order
    last_round = k.round;
    if (k.name == "k:flip_check") {
      ++checks;
      nonempty += k.items > 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(last_round + 1, stats.rounds);
  EXPECT_GE(checks, stats.flip_passes - stats.tail_passes);  // blind passes over empty lists included
  EXPECT_EQ(nonempty, stats.flip_passes - stats.tail_passes);
}

// profile_kernels: the same triangles, and a log of every kernel with its round, with and without the tail
// passes (on by default on GPUs only).
TEST(GpuDelaunay, KernelLogCoversEveryPass) {
  for (bool tail : {false, true}) {
    DelaunayBuilder dt = new_builder();
    dt.profile_kernels = true;
    dt.tail_passes = tail;
    expect_kernel_log(
        expect_cgal(tail ? "profiled, tail: uniform 5k" : "profiled: uniform 5k", uniform(5000, 31), dt));
  }
}

// The Voronoi first stage (issue 30): the same triangles as CGAL (so as the default start) on uniform, clustered,
// grid, duplicate-heavy, collinear and far-apart inputs; where the digital diagram is poor, more insertion, never
// another mesh. On uniform points the start must really be used (no fallback), or the test would prove nothing.
TEST(GpuDelaunay, VoronoiStartMatchesCgal) {
  DelaunayBuilder dt(ctx());
  dt.initial_dt = DelaunayBuilder::Start::voronoi;
  DelaunayStats s = expect_cgal("vd: uniform 20k", uniform(20000, 61), dt);
  EXPECT_TRUE(s.voronoi.used);
  EXPECT_FALSE(s.voronoi.fallback);
  EXPECT_GT(s.voronoi.kept, 20000u * 3 / 4);
  EXPECT_EQ(s.voronoi.kept + s.voronoi.lost, 20000u);
  EXPECT_EQ(s.start_vertices, s.voronoi.kept);
  for (const char* stage : {"vd discretise", "vd flood", "vd dual", "vd repair (host)", "vd flips"})
    EXPECT_TRUE(std::any_of(s.stage_ms.begin(), s.stage_ms.end(), [&](const auto& e) { return e.first == stage; }))
        << stage;
  expect_cgal("vd: clustered", clustered(62, 6, 2000), dt);
  s = expect_cgal("vd: grid 150x100", grid(150, 100, 0, 0, 1), dt);  // co-circular everywhere
  EXPECT_FALSE(s.voronoi.fallback);
  expect_cgal("vd: grid 400x6 utm", grid(400, 6, 500000.25, 6000000.5, 0.5), dt);  // cells shared
  expect_cgal("vd: integers+duplicates", integer_lattice(63), dt);
  std::vector<std::pair<double, double>> far;  // two dense clusters 10^6 apart, nothing between
  Rng r(64);
  for (int i = 0; i < 4000; ++i) far.push_back({r.unit(), r.unit()});
  for (int i = 0; i < 4000; ++i) far.push_back({1e6 + r.unit(), 1e6 + r.unit()});
  far.push_back({0, 1e6});
  expect_cgal("vd: far apart", canonical(far), dt);
  std::vector<std::pair<double, double>> lines;
  for (int i = 0; i < 3000; ++i) lines.push_back({double(i), double(2 * i)});
  lines.push_back({1500, 0});
  lines.push_back({0, 6000});
  expect_cgal("vd: collinear + two", canonical(lines), dt);
  std::vector<std::pair<double, double>> ring;
  for (int i = 0; i < 3000; ++i) {
    const double a = r.uniform(0, 6.283185307179586), d = 1 + r.uniform(0, 1e-3);
    ring.push_back({d * std::cos(a), d * std::sin(a)});
  }
  expect_cgal("vd: ring", canonical(ring), dt);
  expect_same_slots_twice(dt, uniform(15000, 65));
}

// Small lattices (collinear and co-circular everywhere, several points per cell): the Voronoi start's repairs
// and fallbacks on the hardest cases, each compared with CGAL.
TEST(GpuDelaunay, VoronoiStartSmallDegenerateInputs) {
  DelaunayBuilder dt(ctx());
  dt.initial_dt = DelaunayBuilder::Start::voronoi;
  Rng r(66);
  uint32_t used = 0;
  for (int it = 0; it < 120; ++it) {
    const int n = 3 + int(r.g() % (it % 10 == 9 ? 400 : 60)), side = 2 + int(r.g() % (it % 10 == 9 ? 30 : 7));
    std::vector<std::pair<double, double>> pts;
    for (int i = 0; i < n; ++i) pts.push_back({double(r.g() % side), double(r.g() % side) * (it % 2 ? 1.0 : 0.125)});
    std::vector<double> xy = canonical(pts);
    DelaunayStats stats;
    HostTriangulation host = download_host(ctx(), dt.build(xy, &stats));
    if (!host.verts.empty()) {
      ASSERT_EQ(check_triangulation(host), "") << "case " << it;
    }
    ASSERT_EQ(finite_triangles(host), cgal_delaunay(xy)) << "case " << it << ", " << xy.size() / 2 << " points";
    used += stats.voronoi.used && !stats.voronoi.fallback;
  }
  EXPECT_GT(used, 30u);
  no_validation_messages();
}

TEST(GpuDelaunay, Large) {
  if (!large()) GTEST_SKIP() << "set CDTGPU_LARGE=1 (GPU machine) for 1M, 4M and a 2000 x 1000 grid";
  expect_cgal("uniform 1M", uniform(1000000, 11));
  expect_cgal("grid 2000x1000", grid(2000, 1000, 500000, 6000000, 1));
  expect_cgal("uniform 4M", uniform(4000000, 12));
}

TEST(GpuDelaunay, Bench) {
  const char* runs = std::getenv("CDTGPU_DT_BENCH");
  if (!runs) GTEST_SKIP() << "set CDTGPU_DT_BENCH=N (runs) and optionally CDTGPU_DT_BENCH_POINTS";
  const char* pts = std::getenv("CDTGPU_DT_BENCH_POINTS");
  const size_t n = pts ? std::strtoull(pts, nullptr, 10) : 2000000;
  const bool on_grid = env_is("CDTGPU_DT_BENCH_GRID", "1");
  const bool blobs = env_is("CDTGPU_DT_BENCH_CLUSTERED", "1");  // 20 Gaussian blobs over 3000 uniform points
  std::vector<double> xy = on_grid ? grid(2000, uint32_t((n + 1999) / 2000), 500000, 6000000, 1)
                           : blobs ? clustered(13, 20, int(n / 20))
                                   : uniform(n, 13);
  std::printf("[ dt bench ] %zu %s points, %s runs, device %s, %.1f bytes/point\n", xy.size() / 2,
              on_grid ? "grid" : blobs ? "clustered" : "uniform", runs, ctx().info.name.c_str(),
              double(DelaunayBuilder::peak_bytes(uint32_t(xy.size() / 2))) / (xy.size() / 2));
  for (auto& [stage, ms] : bench_delaunay(builder(), xy, std::atoi(runs)))
    std::printf("[ dt bench ] %-10s %9.3f ms (median)\n", stage.c_str(), ms);
  DelaunayStats stats;
  builder().build(xy, &stats);
  std::string passes;
  for (uint32_t p : stats.round_flip_passes) passes.append(" ").append(std::to_string(p));
  std::printf(
      "[ dt bench ] rounds %u (%u sampled), flips %llu, flip passes %u (%u in last workgroups), "
      "dispatched per round:%s\n",
      stats.rounds, stats.sampled_rounds, (unsigned long long)stats.flips, stats.flip_passes,
      stats.tail_passes, passes.c_str());
  if (stats.voronoi.used) {
    const VoronoiStats& v = stats.voronoi;
    std::printf("[ dt bench ] voronoi start: grid %ux%u, sites %u, kept %u, lost %u, repairs %u (%u demoted, %u "
                "flooded in full), fallback %d, start flips %llu in %u passes, %.1f extra bytes/point\n",
                v.grid_width, v.grid_height, v.sites, v.kept, v.lost, v.repairs, v.demoted, v.full_floods,
                int(v.fallback),
                (unsigned long long)v.flips, v.flip_passes, double(v.device_bytes) / double(xy.size() / 2));
  }
  for (size_t r = 0; r < stats.round_log.size(); ++r)
    std::printf("[ dt bench ] round %2zu: %7.3f ms, %8u inserted, %8llu flips, %u passes\n", r,
                stats.round_log[r].ms, stats.round_log[r].inserted,
                (unsigned long long)stats.round_log[r].flips, stats.round_flip_passes[r]);
  if (stats.kernel_log.empty()) return;
  // Where the time goes (CDTGPU_DT_PROFILE_KERNELS=1): per round, and flip passes by list length.
  std::map<uint32_t, std::map<std::string, double>> per_round;
  std::map<uint32_t, uint32_t> list_len;
  for (auto& k : stats.kernel_log) {
    per_round[k.round][k.name] += k.ms;
    if (k.name == "k:relocate") list_len[k.round] = k.items;
  }
  for (auto& [round, kernels] : per_round) {
    std::string line;
    char item[64];
    for (auto& [name, ms] : kernels) {
      std::snprintf(item, sizeof item, " %s %.4f", name.c_str() + 2, ms);
      line += item;
    }
    std::printf("[ dt round %2u ] list %8u:%s\n", round, list_len[round], line.c_str());
  }
  // flip_check and flip of one pass are adjacent in the log: attribute both to the check's list length.
  struct Bucket {
    uint32_t passes = 0;
    double ms = 0;
  };
  std::map<uint32_t, Bucket> pass_len;  // key: decimal digits of the list length
  for (size_t i = 0; i + 1 < stats.kernel_log.size(); ++i) {
    auto& k = stats.kernel_log[i];
    if (k.name != "k:flip_check") continue;
    const uint32_t digits = uint32_t(std::to_string(k.items).size());
    double ms = k.ms;
    for (size_t j = i + 1; j < stats.kernel_log.size() && stats.kernel_log[j].name != "k:flip_check"; ++j)
      if (stats.kernel_log[j].name.rfind("k:flip", 0) == 0) ms += stats.kernel_log[j].ms;
    pass_len[digits].passes += 1;
    pass_len[digits].ms += ms;
  }
  for (auto& [digits, b] : pass_len)
    std::printf("[ dt passes ] list < 1e%u: %4u passes, %8.3f ms (check + flip)\n", digits, b.passes, b.ms);
}
