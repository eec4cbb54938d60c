// core/split_at_vertices against the resolve: segments through vertices, without crossings, split the same
// way.
#include "core/split_at_vertices.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/predicates.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"

namespace cdtgpu {
namespace {

// A 30 x 30 grid; rows of segments at x >= 12 that overlap each other (walls shared in part, equal, nested)
// and columns at x < 12: through grid vertices, never crossing.
PreparedInput rows_and_columns(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> at(0, 29), row_x(12, 29), col_x(0, 11);
  InputSet in;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) in.points.push_back({double(i), double(j), 0});
  auto add = [&](double x0, double y0, double x1, double y1) {
    Polyline l;
    l.points = {{x0, y0, 0}, {x1, y1, 0}};
    in.lines.push_back(std::move(l));
  };
  for (int k = 0; k < 40; ++k) {
    const int y = at(rng) % 6 * 5, x0 = row_x(rng), x1 = row_x(rng);
    if (x0 != x1) add(x0, y, x1, y);
  }
  for (int k = 0; k < 20; ++k) {
    const int x = col_x(rng), y0 = at(rng), y1 = at(rng);
    if (y0 != y1) add(x, y0, x, y1);
  }
  return prepare(in);
}

// The segments with the split ones replaced by their pieces, sorted and unique (equal pieces of collinear
// overlaps merge).
std::vector<Edge> with_pieces(const std::vector<Edge>& segments, const VertexSplits& s) {
  std::vector<Edge> all;
  for (const Edge& e : segments)
    if (!std::binary_search(s.split.begin(), s.split.end(), e)) all.push_back(e);
  all.insert(all.end(), s.pieces.begin(), s.pieces.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

bool inside(const Points& v, Edge s, uint32_t w) {
  auto xy = [&](uint32_t i) { return pred::XY{v[i].x, v[i].y}; };
  return w > s[0] && w < s[1] && pred::orient2d(xy(s[0]), xy(s[1]), xy(w)) == 0;
}

TEST(SplitAtVertices, GivesTheResolvesConstraints) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const PreparedInput p = rows_and_columns(seed);
    const ResolvedInput r = resolve_constraints(p);
    ASSERT_EQ(r.steiner_points, 0u) << seed;
    ASSERT_GT(r.split_at_vertices, 0u) << seed;
    // Every segment with every vertex inside it.
    std::vector<std::array<uint32_t, 3>> all;
    // What tiles report at the least: each such segment with its first vertex, and each vertex once, on the
    // piece of the first segment holding it that runs from the vertex before it.
    std::vector<std::array<uint32_t, 3>> least;
    std::vector<uint8_t> reported(p.vertices.size(), 0);
    for (const Edge& s : p.constraints) {
      uint32_t from = s[0];
      for (uint32_t w = s[0] + 1; w < s[1]; ++w) {
        if (!inside(p.vertices, s, w)) continue;
        all.push_back({s[0], s[1], w});
        if (from == s[0] || !reported[w]) least.push_back({from, s[1], w});
        reported[w] = 1;
        from = w;
      }
    }
    for (const auto& found : {all, least}) {
      const VertexSplits v = split_at_vertices(p.vertices, p.constraints, found);
      EXPECT_EQ(with_pieces(p.constraints, v), r.constraints) << seed;
      EXPECT_EQ(v.splits, r.split_at_vertices) << seed;
    }
  }
}

TEST(SplitAtVertices, NothingFoundLeavesTheSegments) {
  const PreparedInput p = rows_and_columns(3);
  const VertexSplits v = split_at_vertices(p.vertices, p.constraints, {});
  EXPECT_EQ(with_pieces(p.constraints, v), p.constraints);
  EXPECT_TRUE(v.split.empty());
  EXPECT_EQ(v.splits, 0u);
}

}  // namespace
}  // namespace cdtgpu
