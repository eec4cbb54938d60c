// core's duplicate merge (a bucket sort on all cores) against a plain stable sort, on inputs that push the
// buckets to their edges: one x for every point, signed zeros, coordinates near the double limit, a crowd in
// one bucket, sizes around the thresholds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
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
    std::vector<double> uniform(2 * n), lattice(2 * n), one_x(2 * n), huge(2 * n), crowd(2 * n);
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
    }
    expect_reference(uniform, "uniform");
    expect_reference(lattice, "lattice with duplicates");
    expect_reference(one_x, "one x");
    expect_reference(huge, "near the double limit");
    expect_reference(crowd, "a crowd on one x");
  }
}
