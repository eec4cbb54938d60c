// tiled_cdt: k-d tiles by vertex count, each tile's CDT with its final triangles kept, the rest merged by one
// more CDT whose constraints include the final region's border. Why each step is exact: docs/tiles.md.
// Cost: the tiles' CDTs (in parallel) plus the merge, which holds the vertices along the tile borders and
// beside long segments: a few per cent of the input at uniform density (docs/tiles.md has the figures).
#include "core/tiles.hpp"

#include <CGAL/Interval_nt.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "core/canonical.hpp"
#include "core/predicates.hpp"

namespace cdtgpu {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

constexpr double kInf = std::numeric_limits<double>::infinity();

// A tile's closed rectangle; ±inf on the outside of the data. Its vertices may lie on its border (shared with a
// neighbour, each vertex in one of them); every vertex strictly inside it is one of its own.
struct Rect {
  double x0 = -kInf, x1 = kInf, y0 = -kInf, y1 = kInf;
};

struct Node {
  Rect rect;
  uint32_t lo = 0, hi = 0;        // its own vertices: plan.order[lo, hi)
  int32_t left = -1, right = -1;  // children; -1: a tile
  bool x_sorted = false;          // order[lo, hi) is sorted by (x, y)
};

struct Plan {
  std::vector<uint32_t> order;  // vertex ids, each node's a contiguous range
  std::vector<Node> nodes;      // nodes[0]: the root
  std::vector<uint32_t> tiles;  // the leaf nodes, left to right in the tree
};

// k-d splits at the median of the node's longer side (of its vertices' bounding box), level by level, until a
// node holds at most `max_points`. The vertices before the median in (axis, other axis) order go left, so every
// vertex strictly left of the split line is in the left node: by induction, every vertex strictly inside a
// node's rectangle is one of its own.
Plan plan_tiles(const std::vector<Point3>& v, uint64_t max_points) {
  Plan plan;
  plan.order.resize(v.size());
  std::iota(plan.order.begin(), plan.order.end(), 0u);
  plan.nodes.push_back(Node{Rect{}, 0, uint32_t(v.size()), -1, -1, true});
  std::vector<uint32_t> level = {0};
  while (!level.empty()) {
    std::vector<uint32_t> split;
    for (uint32_t i : level)
      if (plan.nodes[i].hi - plan.nodes[i].lo > max_points) split.push_back(i);
    std::vector<std::pair<int, double>> cut(split.size());  // axis (0: x, 1: y) and the median's coordinate
    tbb::parallel_for(size_t(0), split.size(), [&](size_t k) {
      const Node& node = plan.nodes[split[k]];
      uint32_t* b = plan.order.data() + node.lo;
      uint32_t* e = plan.order.data() + node.hi;
      double x0 = kInf, x1 = -kInf, y0 = kInf, y1 = -kInf;
      for (const uint32_t* p = b; p != e; ++p) {
        x0 = std::min(x0, v[*p].x), x1 = std::max(x1, v[*p].x);
        y0 = std::min(y0, v[*p].y), y1 = std::max(y1, v[*p].y);
      }
      const int axis = (x1 - x0 >= y1 - y0) ? 0 : 1;
      uint32_t* mid = b + (e - b) / 2;
      if (axis == 1)
        std::nth_element(b, mid, e, [&](uint32_t p, uint32_t q) {
          return v[p].y != v[q].y ? v[p].y < v[q].y : v[p].x < v[q].x;
        });
      else if (!node.x_sorted)  // vertex ids are in (x, y) order
        std::nth_element(b, mid, e);
      cut[k] = {axis, axis == 0 ? v[*mid].x : v[*mid].y};
    });
    std::vector<uint32_t> next;
    for (size_t k = 0; k < split.size(); ++k) {
      const Node node = plan.nodes[split[k]];
      const uint32_t mid = node.lo + (node.hi - node.lo) / 2;
      Node left = node, right = node;
      left.hi = mid;
      right.lo = mid;
      left.x_sorted = right.x_sorted = node.x_sorted && cut[k].first == 0;
      if (cut[k].first == 0)
        left.rect.x1 = right.rect.x0 = cut[k].second;
      else
        left.rect.y1 = right.rect.y0 = cut[k].second;
      plan.nodes[split[k]].left = int32_t(plan.nodes.size());
      plan.nodes.push_back(left);
      plan.nodes[split[k]].right = int32_t(plan.nodes.size());
      plan.nodes.push_back(right);
      next.push_back(uint32_t(plan.nodes.size() - 2));
      next.push_back(uint32_t(plan.nodes.size() - 1));
    }
    level = std::move(next);
  }
  std::vector<uint32_t> stack = {0};  // leaves left to right
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    if (plan.nodes[i].left < 0)
      plan.tiles.push_back(i);
    else
      stack.push_back(uint32_t(plan.nodes[i].right)), stack.push_back(uint32_t(plan.nodes[i].left));
  }
  return plan;
}

// Whether segment ab meets the closed rectangle r, exactly: the part of r inside the segment's bounding box is
// met exactly when the segment's line does not pass strictly beside all four of its corners.
bool meets(const Rect& r, const Point3& a, const Point3& b) {
  const double x0 = std::max(r.x0, std::min(a.x, b.x)), x1 = std::min(r.x1, std::max(a.x, b.x));
  const double y0 = std::max(r.y0, std::min(a.y, b.y)), y1 = std::min(r.y1, std::max(a.y, b.y));
  if (x0 > x1 || y0 > y1) return false;
  int sides = 0;
  for (const pred::XY c : {pred::XY{x0, y0}, pred::XY{x1, y0}, pred::XY{x0, y1}, pred::XY{x1, y1}})
    sides |= 1 << (1 + pred::orient2d({a.x, a.y}, {b.x, b.y}, c));
  return sides != 1 && sides != 4;  // not all clockwise, not all counter-clockwise
}

// Whether the closed circumdisk of abc lies in the open interior of r, decided in interval arithmetic: a
// triangle too flat or too close to the border to tell is taken as not final, which only makes the merge larger.
// The caller holds CGAL::Protect_FPU_rounding (rounding towards +inf).
bool disk_inside(const Point3& a, const Point3& b, const Point3& c, const Rect& r) {
  using I = CGAL::Interval_nt_advanced;
  const I ax(a.x), ay(a.y);
  const I bx = I(b.x) - ax, by = I(b.y) - ay, cx = I(c.x) - ax, cy = I(c.y) - ay;
  const I d = 2 * (bx * cy - by * cx);
  if (!(d.inf() > 0 || d.sup() < 0)) return false;
  const I b2 = CGAL::square(bx) + CGAL::square(by), c2 = CGAL::square(cx) + CGAL::square(cy);
  const I ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;  // the centre, from a
  const I r2 = CGAL::square(ux) + CGAL::square(uy);
  auto clear = [&](const I& gap) { return gap.inf() > 0 && (CGAL::square(gap) - r2).inf() > 0; };
  return (r.x0 == -kInf || clear(ax + ux - I(r.x0))) && (r.x1 == kInf || clear(I(r.x1) - ax - ux)) &&
         (r.y0 == -kInf || clear(ay + uy - I(r.y0))) && (r.y1 == kInf || clear(I(r.y1) - ay - uy));
}

uint64_t key_of(uint32_t a, uint32_t b) { return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a; }

// The directed edges of `triangles` that no other triangle of the list has: the border of their union, each
// with the union on its left.
std::vector<Edge> border_of(const std::vector<Triangle>& triangles) {
  std::vector<std::pair<uint64_t, Edge>> edges;
  edges.reserve(3 * triangles.size());
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) edges.push_back({key_of(t[k], t[(k + 1) % 3]), {t[k], t[(k + 1) % 3]}});
  std::sort(edges.begin(), edges.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
  std::vector<Edge> border;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j == i + 1) border.push_back(edges[i].second);
    i = j;
  }
  return border;
}

// One tile: its CDT, its final triangles (vertex ids of the whole) and their border.
struct TileResult {
  std::vector<Triangle> final_triangles;
  std::vector<Edge> border;
};

TileResult run_tile(const std::vector<Point3>& v, const std::vector<Edge>& segments, const Plan& plan,
                    const Node& node, std::span<const uint32_t> tile_segments, const TileTriangulator& triangulate,
                    const std::string& name, std::vector<uint8_t>& in_final) {
  std::vector<uint32_t> ids(plan.order.begin() + node.lo, plan.order.begin() + node.hi);
  for (uint32_t s : tile_segments) ids.push_back(segments[s][0]), ids.push_back(segments[s][1]);
  std::sort(ids.begin(), ids.end());  // ids in (x, y) order: the local vertices stay sorted
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<Point3> local(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) local[i] = v[ids[i]];
  auto local_of = [&](uint32_t id) { return uint32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin()); };
  std::vector<Edge> local_segments;
  local_segments.reserve(tile_segments.size());
  for (uint32_t s : tile_segments) local_segments.push_back({local_of(segments[s][0]), local_of(segments[s][1])});
  std::sort(local_segments.begin(), local_segments.end());

  const std::vector<Triangle> triangles = triangulate(local, local_segments, name);
  TileResult r;
  {
    CGAL::Protect_FPU_rounding<true> upward;
    for (const Triangle& t : triangles)
      if (disk_inside(local[t[0]], local[t[1]], local[t[2]], node.rect))
        r.final_triangles.push_back({ids[t[0]], ids[t[1]], ids[t[2]]});
  }
  // A final triangle's vertices are strictly inside the tile, so they are its own: no other tile writes them.
  for (const Triangle& t : r.final_triangles)
    for (uint32_t id : t) in_final[id] = 1;
  r.border = border_of(r.final_triangles);
  return r;
}

// The merge's triangles outside the final region: the merge triangulates the final region's holes too, from
// their border vertices; those triangles lie in parts of the merge, bounded by border edges, that are on the
// final side of a border edge (tiling.md, claim 2). `border` is directed with the final region on its left.
std::vector<Triangle> outside_final(const std::vector<Triangle>& m, const std::vector<Edge>& border) {
  std::vector<std::pair<uint64_t, bool>> final_side;  // key, and whether the final side is left of (min, max)
  final_side.reserve(border.size());
  for (const Edge& e : border) final_side.push_back({key_of(e[0], e[1]), e[0] < e[1]});
  std::sort(final_side.begin(), final_side.end());
  struct HalfEdge {
    uint64_t key;
    uint32_t triangle;
    bool forward;  // the triangle's edge runs from min to max: the triangle is left of (min, max)
  };
  std::vector<HalfEdge> half(3 * m.size());
  tbb::parallel_for(size_t(0), m.size(), [&](size_t t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m[t][k], b = m[t][(k + 1) % 3];
      half[3 * t + k] = {key_of(a, b), uint32_t(t), a < b};
    }
  });
  tbb::parallel_sort(half.begin(), half.end(), [](const HalfEdge& p, const HalfEdge& q) {
    return p.key != q.key ? p.key < q.key : p.triangle < q.triangle;
  });
  std::vector<uint32_t> parent(m.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto root = [&](uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  std::vector<std::pair<uint32_t, bool>> sides;  // a triangle beside a border edge, and whether on its final side
  for (size_t i = 0; i < half.size();) {
    size_t j = i + 1;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    auto f = std::lower_bound(final_side.begin(), final_side.end(), std::pair<uint64_t, bool>{half[i].key, false});
    if (f != final_side.end() && f->first == half[i].key) {
      for (size_t k = i; k < j; ++k) sides.push_back({half[k].triangle, half[k].forward == f->second});
    } else if (j == i + 2) {
      parent[root(half[i].triangle)] = root(half[i + 1].triangle);
    }
    i = j;
  }
  std::vector<uint8_t> mark(m.size(), 0);  // per component root: 1 final side, 2 outside
  for (const auto& [t, on_final] : sides) {
    uint8_t& mk = mark[root(t)];
    const uint8_t want = on_final ? 1 : 2;
    if (mk && mk != want)
      throw std::logic_error("tile merge: a part of the merge lies on both sides of the final region's border");
    mk = want;
  }
  std::vector<Triangle> kept;
  kept.reserve(m.size());
  for (size_t t = 0; t < m.size(); ++t)
    if (mark[root(uint32_t(t))] != 1) kept.push_back(m[t]);
  return kept;
}

}  // namespace

TileTriangulator cgal_tile_triangulator() {
  return [](const std::vector<Point3>& v, const std::vector<Edge>& s, std::string_view) { return cdt_of_graph(v, s); };
}

std::vector<Triangle> tiled_cdt(const std::vector<Point3>& v, const std::vector<Edge>& segments,
                                const TileOptions& options, const TileTriangulator& triangulate, TileStats* stats) {
  TileStats local_stats;
  TileStats& s = stats ? *stats : local_stats;
  const uint64_t n = v.size();
  const uint64_t level = s.levels + 1;
  if (options.max_tile_points < 3 || n <= options.max_tile_points) {
    const auto t = Clock::now();
    std::vector<Triangle> all = triangulate(v, segments, "the whole input");
    s.merge_ms = ms_since(t);
    s.merge_vertices = n;
    s.merge_segments = segments.size();
    s.merge_triangles = all.size();
    return all;
  }
  const auto t_tiles = Clock::now();
  const Plan plan = plan_tiles(v, options.max_tile_points);
  const size_t tiles = plan.tiles.size();
  std::vector<uint32_t> tile_of_node(plan.nodes.size(), 0);
  for (size_t t = 0; t < tiles; ++t) tile_of_node[plan.tiles[t]] = uint32_t(t);

  // Every segment goes to every tile whose rectangle it meets (whole, with its endpoints).
  tbb::enumerable_thread_specific<std::vector<std::pair<uint32_t, uint32_t>>> found;  // (tile, segment)
  tbb::parallel_for(tbb::blocked_range<size_t>(0, segments.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    auto& out = found.local();
    std::vector<uint32_t> stack;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Point3& a = v[segments[i][0]];
      const Point3& b = v[segments[i][1]];
      stack.assign(1, 0);
      while (!stack.empty()) {
        const Node& node = plan.nodes[stack.back()];
        const uint32_t at = stack.back();
        stack.pop_back();
        if (node.left < 0) {
          out.push_back({tile_of_node[at], uint32_t(i)});
          continue;
        }
        for (int32_t c : {node.left, node.right})
          if (meets(plan.nodes[c].rect, a, b)) stack.push_back(uint32_t(c));
      }
    }
  });
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (auto& part : found) pairs.insert(pairs.end(), part.begin(), part.end());
  tbb::parallel_sort(pairs.begin(), pairs.end());
  std::vector<uint32_t> tile_segments(pairs.size());
  std::vector<size_t> first(tiles + 1, 0);
  for (size_t i = 0; i < pairs.size(); ++i) tile_segments[i] = pairs[i].second, ++first[pairs[i].first + 1];
  for (size_t t = 0; t < tiles; ++t) first[t + 1] += first[t];

  std::vector<uint8_t> in_final(n, 0);
  std::vector<TileResult> results(tiles);
  const unsigned threads = options.parallel_tiles ? options.parallel_tiles : std::thread::hardware_concurrency();
  tbb::task_arena arena(int(std::max(1u, threads)));
  arena.execute([&] {
    tbb::parallel_for(size_t(0), tiles, size_t(1), [&](size_t t) {
      const std::span<const uint32_t> mine(tile_segments.data() + first[t], first[t + 1] - first[t]);
      const std::string name = "tile " + std::to_string(t + 1) + " of " + std::to_string(tiles) + ", level " +
                               std::to_string(level);
      results[t] = run_tile(v, segments, plan, plan.nodes[plan.tiles[t]], mine, triangulate, name, in_final);
    });
  });

  // The merge: the vertices not inside the final region, the segments between them (a segment with an end
  // inside the final region lies inside it) and the final region's border.
  std::vector<Triangle> out;
  std::vector<Edge> border;
  for (TileResult& r : results) {
    out.insert(out.end(), r.final_triangles.begin(), r.final_triangles.end());
    border.insert(border.end(), r.border.begin(), r.border.end());
    r = TileResult{};
  }
  std::vector<uint8_t> in_merge(n);
  for (size_t i = 0; i < n; ++i) in_merge[i] = !in_final[i];
  for (const Edge& e : border) in_merge[e[0]] = in_merge[e[1]] = 1;
  std::vector<uint32_t> ids, local_of(n, 0);
  for (uint32_t i = 0; i < n; ++i)
    if (in_merge[i]) local_of[i] = uint32_t(ids.size()), ids.push_back(i);
  std::vector<Point3> merge_vertices(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) merge_vertices[i] = v[ids[i]];
  std::vector<Edge> merge_segments, local_border(border.size());
  for (const Edge& e : segments)
    if (in_merge[e[0]] && in_merge[e[1]]) merge_segments.push_back({local_of[e[0]], local_of[e[1]]});
  for (size_t i = 0; i < border.size(); ++i) {
    local_border[i] = {local_of[border[i][0]], local_of[border[i][1]]};
    merge_segments.push_back({std::min(local_border[i][0], local_border[i][1]),
                              std::max(local_border[i][0], local_border[i][1])});
  }
  tbb::parallel_sort(merge_segments.begin(), merge_segments.end());
  merge_segments.erase(std::unique(merge_segments.begin(), merge_segments.end()), merge_segments.end());
  s.tiles += tiles;
  s.levels += 1;
  s.final_triangles += out.size();
  s.tiles_ms += ms_since(t_tiles);

  // Tiled again while that shrinks it; the last level is one call (its time is merge_ms).
  const bool again = ids.size() > options.max_tile_points && double(ids.size()) <= options.retile_share * double(n);
  std::vector<Triangle> merged;
  if (again) {
    merged = tiled_cdt(merge_vertices, merge_segments, options, triangulate, &s);
  } else {
    const auto t = Clock::now();
    merged = triangulate(merge_vertices, merge_segments, "merge, level " + std::to_string(level));
    s.merge_ms = ms_since(t);
    s.merge_vertices = ids.size();
    s.merge_segments = merge_segments.size();
  }
  const auto t_keep = Clock::now();
  std::vector<Triangle> kept = outside_final(merged, local_border);
  if (!again) s.merge_triangles = kept.size();
  for (Triangle& t : kept) out.push_back({ids[t[0]], ids[t[1]], ids[t[2]]});
  s.tiles_ms += ms_since(t_keep);
  return out;
}

CdtResult triangulate_tiled(ResolvedInput&& in, const TileOptions& options, const TileTriangulator& triangulate,
                            TileStats* stats) {
  CdtResult r;
  r.steiner_points = in.steiner_points;
  r.mesh.triangles = tiled_cdt(in.vertices, in.constraints, options, triangulate, stats);
  r.mesh.vertices = std::move(in.vertices);
  canonicalize(r.mesh);
  return r;
}

uint64_t auto_cpu_tile_points(uint64_t vertices, unsigned cores) {
  constexpr uint64_t kMinPoints = 100'000, kMinTile = 20'000;
  if (cores < 2 || vertices < kMinPoints) return 0;
  return std::max(kMinTile, vertices / (4 * uint64_t(cores)));
}

}  // namespace cdtgpu
