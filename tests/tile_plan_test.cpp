// plan_tiles: every tile at most max_points vertices, every vertex in exactly one tile and inside its closed
// rectangle, every vertex strictly inside a tile's rectangle one of its own (what the tiles' exactness needs),
// on random points (large enough for the parallel selection) and on a grid (ties on every row and column).
#include "core/tile_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

namespace cdtgpu {
namespace {

Points sorted(Points v) {
  std::sort(v.begin(), v.end(), [](const Point3& a, const Point3& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
  return v;
}

bool inside_closed(const TileRect& r, const Point3& p) {
  return p.x >= r.x0 && p.x <= r.x1 && p.y >= r.y0 && p.y <= r.y1;
}
bool strictly_inside(const TileRect& r, const Point3& p) {
  return p.x > r.x0 && p.x < r.x1 && p.y > r.y0 && p.y < r.y1;
}

void expect_plan(const Points& v, uint64_t max_points, const std::string& what,
                 TileShape shape = TileShape::squares, unsigned ramp = 0) {
  const TilePlan plan = plan_tiles(v, max_points, shape, ramp);
  const uint64_t tiles_asked = (v.size() + max_points - 1) / max_points;
  const uint64_t thin = ramp > 1 ? 2 * (ramp - 1) : 0;  // the ramp's extra slabs
  EXPECT_GE(plan.tiles.size(), tiles_asked + thin) << what;
  EXPECT_LE(plan.tiles.size(), tiles_asked + tiles_asked / 2 + 1 + thin) << what;  // columns round the count up
  std::vector<int> owner(v.size(), -1);
  for (size_t t = 0; t < plan.tiles.size(); ++t) {
    const TileNode& node = plan.nodes[plan.tiles[t]];
    EXPECT_LE(node.hi - node.lo, max_points) << what << ", tile " << t;
    for (uint32_t i = node.lo; i < node.hi; ++i) {
      const uint32_t id = plan.id_at(i);
      ASSERT_LT(id, v.size());
      ASSERT_EQ(owner[id], -1) << what << ": vertex " << id << " in two tiles";
      owner[id] = int(t);
      ASSERT_TRUE(inside_closed(node.rect, v[id])) << what << ": vertex " << id << " outside tile " << t;
      ASSERT_TRUE(id >= node.column_lo && id < node.column_hi) << what << ": vertex " << id << " off its column";
    }
    if (shape == TileShape::slabs) {
      EXPECT_EQ(node.hi - node.lo, node.column_hi - node.column_lo) << what << ": tile " << t << " is not a slab";
      EXPECT_EQ(node.lo, node.column_lo) << what << ": a slab's ids are its range";
    }
  }
  for (size_t id = 0; id < v.size(); ++id) {
    ASSERT_NE(owner[id], -1) << what << ": vertex " << id << " in no tile";
    for (size_t t = 0; t < plan.tiles.size(); ++t) {
      if (strictly_inside(plan.nodes[plan.tiles[t]].rect, v[id])) {
        ASSERT_EQ(owner[id], int(t)) << what << ": vertex " << id << " strictly inside tile " << t;
      }
    }
  }
}

// n random points on a grid of eighths `side` wide, sorted and unique (as the resolve leaves them).
Points random_sorted(size_t n, uint64_t seed, uint64_t side) {
  std::mt19937_64 rng(seed);
  Points v(n);
  for (Point3& p : v) p = {double(rng() % side) / 8, double(rng() % side) / 8, 0};
  v = sorted(std::move(v));
  auto same = [](const Point3& a, const Point3& b) { return a.x == b.x && a.y == b.y; };
  v.erase(std::unique(v.begin(), v.end(), same), v.end());
  return v;
}

TEST(TilePlan, RandomPointsInTilesOfAtMostTheirSize) {
  const Points v = random_sorted(3'000'000, 3, 1000000);
  for (uint64_t max_points : {1'600'000ull, 400'000ull, 100'000ull})
    expect_plan(v, max_points, "random, " + std::to_string(max_points));
}

TEST(TilePlan, GridPointsTieOnEveryRowAndColumn) {
  Points v;
  for (int x = 0; x < 300; ++x)
    for (int y = 0; y < 200; ++y) v.push_back({double(x), double(y), 0});
  for (uint64_t max_points : {60'000ull, 7'000ull, 999ull, 16ull})
    expect_plan(v, max_points, "grid, " + std::to_string(max_points));
}

TEST(TilePlan, SlabsAreWholeColumns) {
  const Points v = random_sorted(200'000, 5, 100000);
  for (uint64_t max_points : {60'000ull, 7'000ull})
    expect_plan(v, max_points, "random slabs, " + std::to_string(max_points), TileShape::slabs);
  Points grid;
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 200; ++y) grid.push_back({double(x), double(y), 0});
  expect_plan(grid, 999, "grid slabs, ties on every column", TileShape::slabs);
}

TEST(TilePlan, ARampCutsTheFirstAndTheLastSlab) {
  const Points v = random_sorted(200'000, 9, 100000);
  const size_t n = v.size();
  expect_plan(v, 40'000, "random slabs, a ramp of 3", TileShape::slabs, 3);
  const TilePlan plan = plan_tiles(v, 40'000, TileShape::slabs, 3);
  ASSERT_EQ(plan.tiles.size(), 5u + 4u);  // 5 slabs, the first and the last in three
  std::vector<size_t> sizes;
  for (uint32_t t : plan.tiles) sizes.push_back(plan.nodes[t].hi - plan.nodes[t].lo);
  for (size_t t : {0, 1, 2, 6, 7, 8}) EXPECT_NEAR(double(sizes[t]), double(n) / 15, 1) << "thin slab " << t;
  for (size_t t : {3, 4, 5}) EXPECT_NEAR(double(sizes[t]), double(n) / 5, 1) << "slab " << t;
  // Squares, and slabs too few to cut, take no ramp.
  EXPECT_EQ(plan_tiles(v, 40'000, TileShape::squares, 3).tiles.size(), plan_tiles(v, 40'000).tiles.size());
  EXPECT_EQ(plan_tiles(v, n, TileShape::slabs, 3).tiles.size(), 1u);
  Points grid;
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 200; ++y) grid.push_back({double(x), double(y), 0});
  expect_plan(grid, 999, "grid slabs, ties on every column, a ramp of 4", TileShape::slabs, 4);
}

TEST(TilePlan, AutomaticSlabsOnlyForLargeTilesThatAreNotTooThin) {
  Points v;
  for (int x = 0; x < 64; ++x)
    for (int y = 0; y < 64; ++y) v.push_back({double(x), double(y), 0});
  auto columns = [](const TilePlan& plan) {
    size_t slabs = 0;
    for (uint32_t t : plan.tiles) slabs += plan.nodes[t].hi - plan.nodes[t].lo == plan.nodes[t].column_hi - plan.nodes[t].column_lo;
    return slabs;
  };
  // Small tiles: about square (4 x 4 of 256 points), whatever `automatic` would do for large ones.
  EXPECT_EQ(columns(plan_tiles(v, 256, TileShape::automatic)), 0u);
  EXPECT_EQ(columns(plan_tiles(v, 256, TileShape::slabs)), 16u);
}

TEST(TilePlan, FewerPointsThanATile) {
  const Points v = sorted({{0, 0, 0}, {1, 2, 0}, {2, 1, 0}});
  const TilePlan plan = plan_tiles(v, 10);
  ASSERT_EQ(plan.tiles.size(), 1u);
  EXPECT_EQ(plan.nodes[plan.tiles[0]].hi - plan.nodes[plan.tiles[0]].lo, 3u);
}

}  // namespace
}  // namespace cdtgpu
