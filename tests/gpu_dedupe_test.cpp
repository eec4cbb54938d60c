// Duplicate merging on the GPU against the CPU: same vertices in the same (canonical) order, same map from input
// points to vertices, same first occurrences; and the same vertices as core/prepare.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "core/prepare.hpp"
#include "gpu/context.hpp"
#include "gpu/dedupe.hpp"
#include "gpu/primitives.hpp"
#include "tests/merge_reference.hpp"

using namespace cdtgpu;
using namespace cdtgpu::gpu;

namespace {

Context& ctx() {
  static Context c = [] {
    ContextOptions options;
    options.validation = true;
    return create_context(options);
  }();
  return c;
}

bool large() {
  const char* v = std::getenv("CDTGPU_LARGE");
  return v && std::strcmp(v, "1") == 0;
}

// The CPU answer (tests/merge_reference.hpp), with each vertex's coordinates: its first occurrence's bits.
DedupedHost cpu_dedupe(const std::vector<double>& xy) {
  const PointMerge m = stable_sort_merge(xy);
  DedupedHost h;
  h.map.assign(m.vertex_of.begin(), m.vertex_of.end());
  h.first.assign(m.first.begin(), m.first.end());
  for (uint32_t j : m.first) {
    h.xy.push_back(xy[2 * j]);
    h.xy.push_back(xy[2 * j + 1]);
  }
  return h;
}

void expect_same(const std::vector<double>& xy) {
  DedupedHost gpu = dedupe_points(ctx(), xy);
  DedupedHost cpu = cpu_dedupe(xy);
  ASSERT_EQ(gpu.first.size(), cpu.first.size());
  EXPECT_EQ(gpu.first, cpu.first);
  EXPECT_EQ(gpu.map, cpu.map);
  // Bit-exact: a vertex keeps its first occurrence's bits (-0.0 stays -0.0 if it came first).
  ASSERT_EQ(gpu.xy.size(), cpu.xy.size());
  if (!gpu.xy.empty()) {
    EXPECT_EQ(0, std::memcmp(gpu.xy.data(), cpu.xy.data(), gpu.xy.size() * sizeof(double)));
  }
  EXPECT_TRUE(ctx().messages().empty()) << ctx().messages().front();
}

std::vector<double> integer_points(size_t n, int range, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> d(-range, range);
  std::vector<double> xy(2 * n);
  for (auto& v : xy) v = d(rng);
  return xy;
}

}  // namespace

TEST(GpuDedupe, EmptyAndSinglePoint) {
  expect_same({});
  expect_same({3.5, -2});
}

TEST(GpuDedupe, ManyDuplicatesOnAnIntegerGrid) {
  for (size_t n : {2u, 17u, 1000u, 5000u}) expect_same(integer_points(n, 20, uint32_t(n)));
  expect_same(integer_points(100000, 200, 3));  // every point about 2.5 times
}

TEST(GpuDedupe, NegativeZeroEqualsZeroAndKeepsTheFirstBits) {
  expect_same({-0.0, 1, 0.0, 1, 0.0, -0.0, -0.0, 0.0, -1, -0.0, -1, 0.0, -2.5, 3});
}

TEST(GpuDedupe, UtmScaleWithMillimetreDetail) {
  std::mt19937_64 rng(5);
  std::vector<double> xy;
  for (int i = 0; i < 50000; ++i) {
    double x = 500000 + double(rng() % 10000000) / 1000, y = 6000000 + double(rng() % 1000) / 1000;
    xy.insert(xy.end(), {x, y});
    if (i % 7 == 0) xy.insert(xy.end(), {x, y});  // exact duplicates
    if (i % 11 == 0) xy.insert(xy.end(), {std::nextafter(x, 1e9), y});  // one ulp apart: not a duplicate
  }
  expect_same(xy);
}

TEST(GpuDedupe, SameVerticesAsPrepare) {
  InputSet in;
  auto xy = integer_points(20000, 60, 9);
  for (size_t i = 0; i < xy.size(); i += 2) in.points.push_back({xy[i] * 0.25, xy[i + 1] * 0.5, double(i)});
  for (size_t i = 0; i < xy.size(); i += 2) xy[i] *= 0.25, xy[i + 1] *= 0.5;
  PreparedInput prepared = prepare(in);
  DedupedHost gpu = dedupe_points(ctx(), xy);
  ASSERT_EQ(gpu.first.size(), prepared.vertices.size());
  for (size_t v = 0; v < prepared.vertices.size(); ++v) {
    ASSERT_EQ(gpu.xy[2 * v], prepared.vertices[v].x) << v;
    ASSERT_EQ(gpu.xy[2 * v + 1], prepared.vertices[v].y) << v;
    ASSERT_EQ(in.points[gpu.first[v]].z, prepared.vertices[v].z) << v;  // first occurrence's z, as prepare keeps
  }
}

// The GPU merger inside prepare (what the GPU backend runs) against the CPU merger: every field equal, on
// points with duplicates and z conflicts, -0.0, and lines that share vertices with them and with each other.
TEST(GpuDedupe, PrepareWithTheGpuMergerEqualsTheCpus) {
  Primitives prims(ctx());
  PointDeduper deduper(ctx(), prims);
  const PointMerger gpu = [&](std::span<const double> xy) { return merge_points(deduper, xy); };
  for (uint32_t seed : {1u, 2u, 3u}) {
    InputSet in;
    auto xy = integer_points(3000 * seed, 25, seed);
    for (size_t i = 0; i < xy.size(); i += 2) in.points.push_back({xy[i], xy[i + 1], double(i % 5)});
    in.points.push_back({-0.0, 0.0, 7});
    in.points.push_back({0.0, -0.0, 8});
    std::mt19937 rng(seed);
    for (int l = 0; l < 200; ++l) {
      Polyline line;
      line.closed = l % 3 == 0;
      for (int k = 0; k < 2 + l % 6; ++k)
        line.points.push_back({double(int(rng() % 51) - 25), double(int(rng() % 51) - 25), double(l)});
      in.lines.push_back(line);
    }
    const PreparedInput a = prepare(in), b = prepare(in, gpu);
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    for (size_t v = 0; v < a.vertices.size(); ++v) {
      ASSERT_EQ(0, std::memcmp(&a.vertices[v], &b.vertices[v], sizeof(Point3))) << v;  // bits, -0.0 too
    }
    EXPECT_EQ(a.constraints, b.constraints);
    EXPECT_EQ(a.constraint_line, b.constraint_line);
    EXPECT_EQ(a.merged_duplicates, b.merged_duplicates);
    EXPECT_GT(a.merged_duplicates, 0u);
    EXPECT_EQ(a.z_conflicts, b.z_conflicts);
    EXPECT_GT(a.z_conflicts, 0u);
    EXPECT_EQ(a.max_z_conflict, b.max_z_conflict);
    EXPECT_EQ(a.duplicate_segments, b.duplicate_segments);
    EXPECT_EQ(a.zero_length_segments, b.zero_length_segments);
  }
  EXPECT_TRUE(ctx().messages().empty()) << ctx().messages().front();
}

TEST(GpuDedupe, LargeInputs) {
  if (!large()) GTEST_SKIP() << "set CDTGPU_LARGE=1 (GPU machine)";
  expect_same(integer_points(8u << 20, 3000, 11));
}
