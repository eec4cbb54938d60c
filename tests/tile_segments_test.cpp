// tile_segments: every segment in the list of every tile whose closed rectangle it meets, in segment order.
// Slabs against the closed x-range rule on a grid, where whole columns of vertices lie on the cuts; squares
// against their endpoints; segments out of order refused (the merge input relies on their order too).
#include "core/tile_segments.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

namespace cdtgpu {
namespace {

struct Graph {
  Points v;
  std::vector<Edge> segments;
};

// A 60 x 40 grid sorted by (x, y), and sorted segments: random pairs, pieces of columns (on a cut or not) and
// long rows across every slab.
Graph grid_graph() {
  Graph g;
  for (int x = 0; x < 60; ++x)
    for (int y = 0; y < 40; ++y) g.v.push_back({double(x), double(y), 0});
  const uint32_t n = uint32_t(g.v.size());
  std::mt19937 rng(11);
  for (int i = 0; i < 3000; ++i) {
    const uint32_t a = rng() % n, b = rng() % n;
    if (a != b) g.segments.push_back({std::min(a, b), std::max(a, b)});
  }
  for (uint32_t x = 0; x < 60; ++x) g.segments.push_back({x * 40 + 3, x * 40 + 9});  // along a column
  for (uint32_t y = 0; y < 40; y += 7) g.segments.push_back({y, 59 * 40 + y});       // a whole row
  std::sort(g.segments.begin(), g.segments.end());
  g.segments.erase(std::unique(g.segments.begin(), g.segments.end()), g.segments.end());
  return g;
}

// Also in slabs of 20 points, half a column: slabs of no width, whose cut a segment steps across to reach the
// slab before.
TEST(TileSegments, SlabsGetEverySegmentTheirClosedXRangeMeets) {
  const Graph g = grid_graph();
  for (uint64_t max_points : {300, 130, 1000, 20}) {
    const TilePlan plan = plan_tiles(g.v, max_points, TileShape::slabs);
    ASSERT_TRUE(plan.slabs);
    const TileSegments ts = tile_segments(g.v, g.segments, plan);
    size_t on_cut = 0;
    for (size_t t = 0; t < plan.tiles.size(); ++t) {
      const TileRect& r = plan.nodes[plan.tiles[t]].rect;
      std::vector<uint32_t> expected;
      for (size_t i = 0; i < g.segments.size(); ++i) {
        const double x0 = g.v[g.segments[i][0]].x, x1 = g.v[g.segments[i][1]].x;
        if (std::max(x0, x1) >= r.x0 && std::min(x0, x1) <= r.x1) expected.push_back(uint32_t(i));
        on_cut += x0 == r.x0 || x1 == r.x0;
      }
      RawVector<uint32_t> scratch;
      const std::span<const uint32_t> got = ts.of(t, scratch);
      EXPECT_EQ(std::vector<uint32_t>(got.begin(), got.end()), expected) << max_points << ", slab " << t;
    }
    EXPECT_GT(on_cut, 0u) << "some segment ends on a cut";
    if (max_points == 20) {
      EXPECT_TRUE(std::any_of(plan.tiles.begin(), plan.tiles.end(),
                              [&](uint32_t t) { return plan.nodes[t].rect.x0 == plan.nodes[t].rect.x1; }))
          << "a slab of no width";
    }
  }
}

TEST(TileSegments, SquaresGetEverySegmentWithAnEndInTheirRectangle) {
  const Graph g = grid_graph();
  const TilePlan plan = plan_tiles(g.v, 200, TileShape::squares);
  ASSERT_FALSE(plan.slabs);
  const TileSegments ts = tile_segments(g.v, g.segments, plan);
  for (size_t t = 0; t < plan.tiles.size(); ++t) {
    const TileRect& r = plan.nodes[plan.tiles[t]].rect;
    RawVector<uint32_t> scratch;
    const std::span<const uint32_t> got = ts.of(t, scratch);
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    for (size_t i = 0; i < g.segments.size(); ++i)
      for (uint32_t id : g.segments[i]) {
        const Point3& p = g.v[id];
        if (p.x >= r.x0 && p.x <= r.x1 && p.y >= r.y0 && p.y <= r.y1) {
          EXPECT_TRUE(std::binary_search(got.begin(), got.end(), uint32_t(i)))
              << "tile " << t << ", segment " << i;
        }
      }
  }
}

TEST(TileSegments, SegmentsOutOfOrderAreRefused) {
  for (TileShape shape : {TileShape::slabs, TileShape::squares}) {
    Graph g = grid_graph();
    const TilePlan plan = plan_tiles(g.v, 300, shape);
    std::swap(g.segments[10], g.segments[2000]);
    EXPECT_THROW(tile_segments(g.v, g.segments, plan), std::logic_error);
    g = grid_graph();
    std::swap(g.segments[5][0], g.segments[5][1]);
    EXPECT_THROW(tile_segments(g.v, g.segments, plan), std::logic_error);
  }
}

}  // namespace
}  // namespace cdtgpu
