// core/tile_merge: RunMerge puts a mesh split into tile runs and a merge run back into canonical order (into
// room made ahead or not); outside_final drops exactly the merge's triangles on the final side of the
// border, and refuses a border whose sides disagree.
#include "core/tile_merge.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <stdexcept>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/workloads.hpp"

namespace cdtgpu {
namespace {

// A real canonical mesh split as core/tiles splits it: vertices in `tiles` id ranges (slabs); a triangle of one
// range's vertices goes to that range's run unless the dice take it; every other triangle to the merge's run,
// last. Interleaved: each triangle to a run by the dice, as square tiles' runs interleave.
std::vector<Triangles> split_runs(const Triangles& all, size_t vertices, size_t tiles, bool interleaved,
                                  std::mt19937_64& rng) {
  std::vector<Triangles> runs(tiles + 1);
  auto tile_of = [&](uint32_t v) { return size_t(v) * tiles / vertices; };
  for (const Triangle& t : all) {
    if (interleaved) {
      runs[rng() % runs.size()].push_back(t);
      continue;
    }
    const size_t a = tile_of(t[0]);
    const bool own = a == tile_of(t[1]) && a == tile_of(t[2]) && rng() % 5 != 0;
    runs[own ? a : tiles].push_back(t);
  }
  return runs;
}

TEST(RunMerge, PutsTileRunsAndTheMergeBackInCanonicalOrder) {
  InputSet in = uniform_points(30000, 3);
  add_dt_edge_constraints(in, 5000, 0.5, 3);
  const CdtResult r = triangulate_cgal(prepare(in));
  const size_t n = r.mesh.vertices.size(), total = r.mesh.triangles.size();
  std::mt19937_64 rng(8);
  for (size_t tiles : {1, 3, 16})
    for (bool interleaved : {false, true}) {
      const std::vector<Triangles> runs = split_runs(r.mesh.triangles, n, tiles, interleaved, rng);
      // With the output's room made ahead (as large as asked, or too small: then left for a fresh one) and
      // without; in one wave and in many.
      for (size_t room : {size_t(0), 2 * n, total - 1})
        for (size_t wave_bytes : {size_t(512) << 20, total * sizeof(Triangle) / 7}) {
          std::vector<Triangles> copy = runs;
          RunMerge order;
          if (room) order.make_room(room, 2);
          EXPECT_EQ(order.merge(copy, wave_bytes), r.mesh.triangles)
              << tiles << " tiles, interleaved " << interleaved << ", room " << room << ", wave " << wave_bytes;
          for (const Triangles& run : copy) EXPECT_TRUE(run.empty());
        }
    }
  std::vector<Triangles> none(3);
  EXPECT_TRUE(RunMerge().merge(none).empty());
}

// RunMerge::in_place: the same order as merge, left in the runs: every span inside a run, read back in any
// range; split only where runs interleave; take() gives the one array and frees the runs.
TEST(RunMerge, LeavesTheOrderInTheRuns) {
  InputSet in = uniform_points(30000, 4);
  add_dt_edge_constraints(in, 5000, 0.5, 4);
  const CdtResult r = triangulate_cgal(prepare(in));
  const Triangles& all = r.mesh.triangles;
  const size_t n = r.mesh.vertices.size(), total = all.size();
  std::mt19937_64 rng(9);
  for (size_t tiles : {1, 3, 16})
    for (bool interleaved : {false, true}) {
      std::vector<Triangles> runs = split_runs(all, n, tiles, interleaved, rng);
      std::vector<std::pair<const Triangle*, const Triangle*>> held;
      for (const Triangles& run : runs) held.emplace_back(run.data(), run.data() + run.size());
      const size_t merge_run = runs.back().size();
      OrderedRuns o = RunMerge().in_place(std::move(runs));
      const std::string what = std::to_string(tiles) + " tiles, interleaved " + std::to_string(interleaved);
      ASSERT_EQ(o.size(), total) << what;
      Triangles read;
      o.spans().each(0, total, [&](std::span<const Triangle> s) {
        EXPECT_FALSE(s.empty()) << what;
        EXPECT_TRUE(std::any_of(held.begin(), held.end(), [&](const auto& h) {
          return s.data() >= h.first && s.data() + s.size() <= h.second;
        })) << what;
        read.insert(read.end(), s.begin(), s.end());
      });
      EXPECT_EQ(read, all) << what;
      // Not split triangle by triangle: slabs' runs only where the merge's triangles fall among them.
      if (!interleaved) {
        EXPECT_LE(o.spans().span_count(), 2 * merge_run + tiles + 16384) << what;
      }
      for (int k = 0; k < 50; ++k) {
        const size_t first = rng() % total, count = rng() % (total - first + 1);
        Triangles part;
        o.spans().each(first, count, [&](std::span<const Triangle> s) { part.insert(part.end(), s.begin(), s.end()); });
        EXPECT_TRUE(std::equal(part.begin(), part.end(), all.begin() + first, all.begin() + first + count) &&
                    part.size() == count)
            << what << ", from " << first << ", " << count;
      }
      EXPECT_EQ(std::move(o).take(), all) << what;
      EXPECT_TRUE(o.empty());
    }
  std::vector<Triangles> none(3);
  EXPECT_TRUE(RunMerge().in_place(std::move(none)).empty());
  Triangles one = all;
  const Triangle* storage = one.data();
  Triangles back = OrderedRuns(std::move(one)).take();
  EXPECT_EQ(back.data(), storage);  // one run that is all of them: moved, not copied
}

// Points around (and on) rectangles whose sides are the border: no point strictly inside one, as in a merge.
struct Holes {
  Points vertices;
  std::vector<Edge> border;  // counter-clockwise around each rectangle: the final region on the left
};

Holes holes_in_points() {
  const std::vector<std::array<double, 4>> rects = {{20, 45, 30, 70}, {60, 85, 10, 40}};
  auto inside = [&](double x, double y) {
    for (const auto& q : rects)
      if (x >= q[0] && x <= q[1] && y >= q[2] && y <= q[3]) return true;
    return false;
  };
  Points pts;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 100);
  while (pts.size() < 3000) {
    const double x = u(rng), y = u(rng);
    if (!inside(x, y)) pts.push_back({x, y, 0});
  }
  std::vector<std::vector<Point3>> rings;
  for (const auto& q : rects) {
    std::vector<Point3> ring;
    for (int k = 0; k < 10; ++k) ring.push_back({q[0] + (q[1] - q[0]) * k / 10, q[2], 0});
    for (int k = 0; k < 10; ++k) ring.push_back({q[1], q[2] + (q[3] - q[2]) * k / 10, 0});
    for (int k = 0; k < 10; ++k) ring.push_back({q[1] - (q[1] - q[0]) * k / 10, q[3], 0});
    for (int k = 0; k < 10; ++k) ring.push_back({q[0], q[3] - (q[3] - q[2]) * k / 10, 0});
    pts.insert(pts.end(), ring.begin(), ring.end());
    rings.push_back(ring);
  }
  auto less = [](const Point3& a, const Point3& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; };
  std::sort(pts.begin(), pts.end(), less);
  Holes h;
  h.vertices = pts;
  auto id = [&](const Point3& p) { return uint32_t(std::lower_bound(pts.begin(), pts.end(), p, less) - pts.begin()); };
  for (const auto& ring : rings)
    for (size_t k = 0; k < ring.size(); ++k) h.border.push_back({id(ring[k]), id(ring[(k + 1) % ring.size()])});
  return h;
}

TEST(OutsideFinal, DropsTheTrianglesOnTheBordersFinalSide) {
  const Holes h = holes_in_points();
  std::vector<Edge> segments;
  for (const Edge& e : h.border) segments.push_back({std::min(e[0], e[1]), std::max(e[0], e[1])});
  std::sort(segments.begin(), segments.end());
  Triangles merge = cdt_of_graph(h.vertices, segments);
  canonicalize_triangles(merge);  // as a merge's triangles come
  const uint32_t V = uint32_t(h.vertices.size());
  auto in_a_hole = [&](const Triangle& t) {
    const double x = (h.vertices[t[0]].x + h.vertices[t[1]].x + h.vertices[t[2]].x) / 3;
    const double y = (h.vertices[t[0]].y + h.vertices[t[1]].y + h.vertices[t[2]].y) / 3;
    return (x > 20 && x < 45 && y > 30 && y < 70) || (x > 60 && x < 85 && y > 10 && y < 40);
  };
  Triangles outside, inside;
  for (const Triangle& t : merge) (in_a_hole(t) ? inside : outside).push_back(t);
  ASSERT_GT(inside.size(), 20u);
  EXPECT_EQ(outside_final(merge, V, h.border), outside);
  // The border turned round: the final region is now outside the rectangles.
  std::vector<Edge> reversed;
  for (const Edge& e : h.border) reversed.push_back({e[1], e[0]});
  EXPECT_EQ(outside_final(merge, V, reversed), inside);
  // One edge turned round: a part on both sides of the border.
  std::vector<Edge> broken = h.border;
  std::swap(broken[5][0], broken[5][1]);
  EXPECT_THROW(outside_final(merge, V, broken), std::logic_error);
  // Out of canonical order: its adjacency would be wrong, so it is refused.
  Triangles shuffled = merge;
  std::swap(shuffled[0], shuffled[1]);
  EXPECT_THROW(outside_final(shuffled, V, h.border), std::logic_error);
}

}  // namespace
}  // namespace cdtgpu
