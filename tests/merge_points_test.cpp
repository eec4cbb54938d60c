// core's duplicate merge (a bucket sort on all cores) against a plain stable sort, on inputs that push the
// buckets to their edges: one x for every point, signed zeros, coordinates near the double limit, a crowd in
// one bucket, many points on few x, sizes around the thresholds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/prepare.hpp"
#include "tests/merge_reference.hpp"

using namespace cdtgpu;

namespace {

void expect_reference(const std::vector<double>& xy, const char* what) {
  const PointMerge got = merge_points(xy), want = stable_sort_merge(xy);
  EXPECT_EQ(got.first, want.first) << what << ", " << xy.size() / 2 << " points";
  EXPECT_EQ(got.vertex_of, want.vertex_of) << what << ", " << xy.size() / 2 << " points";
}

}  // namespace

TEST(MergePoints, EqualsAStableSort) {
  std::mt19937_64 rng(7);
  for (size_t n : {0, 1, 2, 63, 64, 65, 1000, 40000, 300000}) {
    std::vector<double> uniform(2 * n), lattice(2 * n), one_x(2 * n), huge(2 * n), crowd(2 * n), columns(2 * n);
    std::uniform_real_distribution<double> u(0, 1e4);
    for (size_t i = 0; i < n; ++i) {
      uniform[2 * i] = 500000 + std::floor(u(rng) * 1000) / 1000;  // UTM metres, millimetre grid
      uniform[2 * i + 1] = 6000000 + std::floor(u(rng) * 1000) / 1000;
      lattice[2 * i] = double(rng() % 300);  // many exact duplicates, few distinct x
      lattice[2 * i + 1] = double(rng() % 300);
      one_x[2 * i] = (rng() & 1) ? -0.0 : 0.0;  // a vertical line: one bucket, signed zeros equal
      one_x[2 * i + 1] = double(rng() % 5000);
      huge[2 * i] = (rng() % 3 == 0) ? std::numeric_limits<double>::max() : -1e308 * double(rng() % 2);
      huge[2 * i + 1] = double(rng() % 7);  // an x range that overflows a double
      const bool in_crowd = rng() % 4 != 0;  // three quarters on x = 5: one crowded bucket
      crowd[2 * i] = in_crowd ? 5.0 : u(rng);
      crowd[2 * i + 1] = in_crowd ? double(rng() % 100000) : u(rng);
      // Few x, each with many points (a grid DEM's columns): the small sort's buckets by y, with long runs of one
      // (x, y), y spread over powers of two (ranges the buckets hardly split) and y at the double limit.
      columns[2 * i] = 100 + double(rng() % 50);
      const uint64_t r = rng() % 10;
      const double top = std::numeric_limits<double>::max();
      columns[2 * i + 1] = r < 6   ? double(rng() % 100)
                           : r < 8 ? std::ldexp(1.0, int(rng() % 900))
                           : r < 9 ? double(rng() % 100000) / 7
                                   : ((rng() & 1) ? top : -top);
    }
    expect_reference(uniform, "uniform");
    expect_reference(lattice, "lattice with duplicates");
    expect_reference(one_x, "one x");
    expect_reference(huge, "near the double limit");
    expect_reference(crowd, "a crowd on one x");
    expect_reference(columns, "columns of many points on one x");
  }
}

// One crowded coarse bucket over all its fine ones (core/merge_points.cpp): 2.5M points, nine in ten in a band of
// x one 4096th of the range wide, on a millimetre grid with duplicates. The crowded bucket is the first, so while
// it is sorted the other workers' buckets wait for its count: nearly all are written back and emitted after the
// sort (the other path of the merge; on the uniform inputs above nearly all are emitted from the sort's buffers).
TEST(MergePoints, CrowdedCoarseBucketOverItsFineOnes) {
  std::mt19937_64 rng(11);
  const size_t n = 2500000;
  std::vector<double> band(2 * n);
  for (size_t i = 0; i < n; ++i) {
    const bool in_band = rng() % 10 != 0;
    band[2 * i] = double(rng() % (in_band ? 1000 : 4096000)) / 1000;
    band[2 * i + 1] = double(rng() % 2000) / 1000;
  }
  expect_reference(band, "a band of x in one coarse bucket");
}

// The x range comes from a sample of 2^20 points less its outer 1/8192 (core/merge_points.cpp): far outliers
// and points the sample may skip fall outside it, into the end buckets, with duplicates among them and with the
// points inside. 1.5M points, so the sample skips some.
TEST(MergePoints, PointsOutsideTheSampledRange) {
  std::mt19937_64 rng(13);
  const size_t n = 1500000;
  std::vector<double> xy(2 * n);
  for (size_t i = 0; i < n; ++i) {
    xy[2 * i] = 500000 + double(rng() % 1000000) / 100;
    xy[2 * i + 1] = double(rng() % 1000);
  }
  for (size_t i = 0; i < n; i += 9973) xy[2 * i] = (rng() & 1) ? 1e12 : -1e9 - double(rng() % 3);  // outliers
  xy[2 * 700001] = 0;  // one point, far below the rest
  for (size_t i = 300000; i < 300040; ++i) xy[2 * i] = 510000 + double(i % 4);  // past the top, duplicates
  xy[2 * 5] = 0, xy[2 * 5 + 1] = 7;
  xy[2 * 9] = 0, xy[2 * 9 + 1] = 7;
  expect_reference(xy, "outliers");
}

namespace {

// Every field of prepare's own merge (merge_input, reading the input where it is; the points freed once read)
// against the coordinates' merge (merge_points after the gather, the GPU merger's path), vertices bit for bit.
void expect_both_paths_equal(const InputSet& in, const char* what) {
  // The CLI frees the points once they are read (prepare's `gathered`): the same result.
  InputSet freed = in;
  const PreparedInput a = prepare(freed, {}, [&] { free_storage(freed.points); }), b = prepare(in, merge_points);
  ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
  for (size_t v = 0; v < a.vertices.size(); ++v)
    ASSERT_EQ(0, std::memcmp(&a.vertices[v], &b.vertices[v], sizeof(Point3))) << what << ", vertex " << v;
  EXPECT_EQ(a.constraints, b.constraints) << what;
  EXPECT_EQ(a.constraint_line, b.constraint_line) << what;
  EXPECT_EQ(a.input_points, b.input_points) << what;
  EXPECT_EQ(a.merged_duplicates, b.merged_duplicates) << what;
  EXPECT_EQ(a.z_conflicts, b.z_conflicts) << what;
  EXPECT_EQ(a.max_z_conflict, b.max_z_conflict) << what;
  EXPECT_EQ(a.input_segments, b.input_segments) << what;
  EXPECT_EQ(a.duplicate_segments, b.duplicate_segments) << what;
  EXPECT_EQ(a.zero_length_segments, b.zero_length_segments) << what;
}

}  // namespace

// Duplicates with and without z conflicts (groups at the buckets' edges), signed zeros, lines
// sharing points with the loose points and each other, empty lines, no loose points at all.
TEST(MergeInput, SameAsTheGatheredMerge) {
  std::mt19937_64 rng(11);
  for (size_t n : {0, 1, 5, 100, 70000, 300000}) {
    InputSet in;
    for (size_t i = 0; i < n; ++i) {
      const double x = double(rng() % 400), y = double(rng() % 400);  // many duplicates
      const double z = rng() % 3 == 0 ? double(rng() % 4) : 1.0;      // some of them conflicting
      in.points.push_back({i % 7 == 0 && x == 0 ? -0.0 : x, y, z});
    }
    for (int l = 0; l < 300; ++l) {
      Polyline line;
      line.closed = l % 4 == 0;
      for (int k = 0; k < l % 9; ++k)
        line.points.push_back({double(rng() % 400), double(rng() % 400) - (k % 2 ? 0.0 : -0.0), double(l % 5)});
      in.lines.push_back(line);
    }
    expect_both_paths_equal(in, "points and lines");
    in.points.clear();
    expect_both_paths_equal(in, "lines only");
  }
}

// One non-finite coordinate: the same message (the first such occurrence's index) on both paths.
TEST(MergeInput, NonFiniteCoordinateNamesTheSameVertex) {
  for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    InputSet in;
    for (int i = 0; i < 50000; ++i) in.points.push_back({double(i % 300), double(i / 300), 0});
    Polyline line;
    line.points = {{1, 1, 0}, {2, 2, bad}, {3, bad, 0}};
    in.lines.push_back(line);
    std::string a, b;
    try {
      prepare(in);
    } catch (const std::invalid_argument& e) {
      a = e.what();
    }
    try {
      prepare(in, merge_points);
    } catch (const std::invalid_argument& e) {
      b = e.what();
    }
    EXPECT_EQ(a, "prepare: vertex 50001 is not finite");
    EXPECT_EQ(a, b);
  }
}

// prepare's segments against an independent count: each line point's vertex found by search among the prepared
// vertices, the segments sorted plainly. 1.2M segments of 2000 lines on a small grid, so many are shared,
// repeated or zero-length.
TEST(PrepareSegments, SameAsAPlainSortOfTheSegments) {
  std::mt19937_64 rng(5);
  InputSet in;
  for (int l = 0; l < 2000; ++l) {
    Polyline line;
    line.closed = l % 5 == 0;
    for (int k = 0; k < 601; ++k) line.points.push_back({double(rng() % 700), double(rng() % 700), 0.0});
    in.lines.push_back(line);
  }
  const PreparedInput p = prepare(in);
  auto vertex = [&](const Point3& q) {
    const auto it = std::lower_bound(p.vertices.begin(), p.vertices.end(), q, [](const Point3& a, const Point3& b) {
      return a.x != b.x ? a.x < b.x : a.y < b.y;
    });
    return uint32_t(it - p.vertices.begin());
  };
  struct Key {
    uint32_t a, b, line;
  };
  std::vector<Key> keys;
  for (uint32_t l = 0; l < in.lines.size(); ++l) {
    const Points& q = in.lines[l].points;
    const size_t segments = in.lines[l].closed ? q.size() : q.size() - 1;
    for (size_t k = 0; k < segments; ++k) {
      const uint32_t u = vertex(q[k]), w = vertex(q[(k + 1) % q.size()]);
      if (u != w) keys.push_back({std::min(u, w), std::max(u, w), l});
    }
  }
  ASSERT_GT(keys.size(), size_t(1) << 20);
  std::sort(keys.begin(), keys.end(), [](const Key& s, const Key& t) {
    return s.a != t.a ? s.a < t.a : s.b != t.b ? s.b < t.b : s.line < t.line;
  });
  std::vector<Edge> want;
  std::vector<uint32_t> want_line;
  for (size_t i = 0; i < keys.size(); ++i)
    if (i == 0 || keys[i].a != keys[i - 1].a || keys[i].b != keys[i - 1].b) {
      want.push_back({keys[i].a, keys[i].b});
      want_line.push_back(keys[i].line);
    }
  EXPECT_EQ(p.constraints, want);
  EXPECT_EQ(std::vector<uint32_t>(p.constraint_line.begin(), p.constraint_line.end()), want_line);
}
