// verify_mesh: checks a mesh against its prepared input with CGAL's exact predicates (Epick), independently
// of how the mesh was built. Half-edges go into per-vertex sorted lists (CSR), so every check is O(n log n).
//
// Why these checks make a valid triangulation: with every triangle strictly CCW, every edge used at most once
// per direction, and the unpaired half-edges forming one cycle that walks the convex hull once CCW, every
// point inside the hull is covered by exactly one triangle (the triangles form a 2-chain whose boundary winds
// once around it). Constrained-Delaunay then is local: every non-constrained interior edge passes CGAL's
// perturbed incircle test.
#include "core/verify.hpp"

#include <CGAL/Convex_hull_traits_adapter_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_2.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string vtx(const Points& vs, uint32_t i) {
  std::string s = "vertex " + std::to_string(i);
  if (i < vs.size()) s += " (" + num(vs[i].x) + ", " + num(vs[i].y) + ")";
  return s;
}

std::string tri(const Triangles& ts, size_t t) {
  return "triangle " + std::to_string(t) + " (" + std::to_string(ts[t][0]) + ", " + std::to_string(ts[t][1]) +
         ", " + std::to_string(ts[t][2]) + ")";
}

struct Collector {
  VerifyReport& report;
  size_t cap;
  uint64_t dropped = 0;
  void add(std::string s) {
    if (report.failures.size() < cap)
      report.failures.push_back(std::move(s));
    else
      ++dropped;
  }
  void finish() {
    if (dropped) report.failures.push_back("... and " + std::to_string(dropped) + " more failures");
  }
};

struct HalfEdge {
  uint32_t to, tri, opp;  // a -> to in triangle tri, whose third vertex is opp
};

// Triangle-free case: only two or fewer vertices, or all of them on one line, may give no triangles.
bool collinear(const std::vector<P2>& p) {
  size_t j = 1;
  while (j < p.size() && p[j] == p[0]) ++j;
  for (size_t i = j + 1; i < p.size(); ++i)
    if (CGAL::orientation(p[0], p[j], p[i]) != CGAL::COLLINEAR) return false;
  return true;
}

}  // namespace

VerifyReport verify_mesh(const Mesh& mesh, const PreparedInput& prepared, size_t max_failures,
                         std::vector<Edge>* constrained_edges) {
  VerifyReport report;
  Collector fail{report, std::max<size_t>(max_failures, 1)};
  const Points& mv = mesh.vertices;
  const Triangles& ts = mesh.triangles;
  const uint32_t V = uint32_t(mv.size());
  std::vector<P2> P;
  P.reserve(V);
  for (const Point3& p : mv) P.emplace_back(p.x, p.y);

  // Vertices: unique (x, y); every prepared vertex present with its z.
  std::vector<uint32_t> by_xy(V);
  std::iota(by_xy.begin(), by_xy.end(), 0u);
  auto xy_less = [&](uint32_t a, uint32_t b) {
    return mv[a].x != mv[b].x ? mv[a].x < mv[b].x : mv[a].y != mv[b].y ? mv[a].y < mv[b].y : a < b;
  };
  std::sort(by_xy.begin(), by_xy.end(), xy_less);
  for (size_t i = 1; i < by_xy.size(); ++i)
    if (mv[by_xy[i]].x == mv[by_xy[i - 1]].x && mv[by_xy[i]].y == mv[by_xy[i - 1]].y)
      fail.add(vtx(mv, by_xy[i - 1]) + " and " + vtx(mv, by_xy[i]) + " are the same point");
  std::vector<uint8_t> is_input(V, 0);
  std::vector<uint32_t> mesh_of(prepared.vertices.size(), kNone);
  for (uint32_t i = 0; i < prepared.vertices.size(); ++i) {
    const Point3& p = prepared.vertices[i];
    auto it = std::lower_bound(by_xy.begin(), by_xy.end(), p, [&](uint32_t a, const Point3& q) {
      return mv[a].x != q.x ? mv[a].x < q.x : mv[a].y < q.y;
    });
    if (it == by_xy.end() || mv[*it].x != p.x || mv[*it].y != p.y) {
      fail.add("input vertex " + std::to_string(i) + " (" + num(p.x) + ", " + num(p.y) +
               ") is not in the mesh");
      continue;
    }
    if (mv[*it].z != p.z)
      fail.add("input vertex " + std::to_string(i) + " (" + num(p.x) + ", " + num(p.y) + ") has z " +
               num(p.z) + " but mesh " + vtx(mv, *it) + " has z " + num(mv[*it].z));
    mesh_of[i] = *it;
    is_input[*it] = 1;
  }

  if (ts.empty()) {
    if (!collinear(P)) fail.add("the mesh has no triangles but its vertices are not all on one line");
    for (uint32_t v = 0; v < V; ++v)
      if (!is_input[v]) fail.add(vtx(mv, v) + " is not an input vertex (and no constraints can cross here)");
    fail.finish();
    return report;
  }

  // Triangles: indices in range, strictly CCW, no duplicates.
  bool bad_index = false;
  for (size_t t = 0; t < ts.size(); ++t)
    if (ts[t][0] >= V || ts[t][1] >= V || ts[t][2] >= V) {
      fail.add(tri(ts, t) + " has a vertex index out of range (" + std::to_string(V) + " vertices)");
      bad_index = true;
    }
  if (bad_index || ts.size() >= kNone / 3) {
    fail.finish();
    return report;
  }
  for (size_t t = 0; t < ts.size(); ++t) {
    const CGAL::Orientation o = CGAL::orientation(P[ts[t][0]], P[ts[t][1]], P[ts[t][2]]);
    if (o != CGAL::LEFT_TURN)
      fail.add(tri(ts, t) + (o == CGAL::COLLINEAR ? " is degenerate (collinear vertices)" : " is clockwise") +
               ": " + vtx(mv, ts[t][0]) + ", " + vtx(mv, ts[t][1]) + ", " + vtx(mv, ts[t][2]));
  }
  {
    std::vector<std::pair<Triangle, uint32_t>> rot(ts.size());
    for (size_t t = 0; t < ts.size(); ++t) {
      const Triangle& r = ts[t];
      const int k = int(std::min_element(r.begin(), r.end()) - r.begin());
      rot[t] = {{r[k], r[(k + 1) % 3], r[(k + 2) % 3]}, uint32_t(t)};
    }
    std::sort(rot.begin(), rot.end());
    for (size_t i = 1; i < rot.size(); ++i)
      if (rot[i].first == rot[i - 1].first)
        fail.add(tri(ts, rot[i - 1].second) + " and " + tri(ts, rot[i].second) + " are the same triangle");
  }

  // Half-edges per vertex, sorted by target.
  std::vector<uint32_t> first(size_t(V) + 1, 0);
  for (const Triangle& t : ts)
    for (uint32_t a : t) ++first[a + 1];
  for (uint32_t v = 0; v < V; ++v) first[v + 1] += first[v];
  std::vector<HalfEdge> he(ts.size() * 3);
  {
    std::vector<uint32_t> cursor(first.begin(), first.end() - 1);
    for (uint32_t t = 0; t < ts.size(); ++t)
      for (int k = 0; k < 3; ++k) he[cursor[ts[t][k]]++] = {ts[t][(k + 1) % 3], t, ts[t][(k + 2) % 3]};
  }
  for (uint32_t v = 0; v < V; ++v)
    std::sort(he.begin() + first[v], he.begin() + first[v + 1], [](const HalfEdge& a, const HalfEdge& b) {
      return a.to != b.to ? a.to < b.to : a.tri < b.tri;
    });
  auto find_half_edge = [&](uint32_t a, uint32_t b) {
    auto lo = he.begin() + first[a], hi = he.begin() + first[a + 1];
    auto it = std::lower_bound(lo, hi, b, [](const HalfEdge& e, uint32_t to) { return e.to < to; });
    return it != hi && it->to == b ? uint32_t(it - he.begin()) : kNone;
  };

  std::vector<uint32_t> twin(he.size(), kNone);
  std::vector<uint32_t> bnext(V, kNone), bprev(V, kNone);
  uint64_t boundary_edges = 0, paired = 0;
  for (uint32_t v = 0; v < V; ++v) {
    if (first[v] == first[v + 1]) fail.add(vtx(mv, v) + " is in no triangle");
    for (uint32_t h = first[v]; h < first[v + 1]; ++h) {
      const uint32_t w = he[h].to;
      if (h > first[v] && he[h - 1].to == w) {
        fail.add("edge " + std::to_string(v) + " -> " + std::to_string(w) +
                 " is used in the same direction by " + tri(ts, he[h - 1].tri) + " and " +
                 tri(ts, he[h].tri) + " (overlap or fold)");
        continue;
      }
      twin[h] = find_half_edge(w, v);
      if (twin[h] != kNone) {
        ++paired;
        continue;
      }
      ++boundary_edges;
      if (bnext[v] != kNone)
        fail.add(vtx(mv, v) + " has two boundary edges leaving it (to " + std::to_string(bnext[v]) + " and " +
                 std::to_string(w) + "): the boundary is not one simple cycle");
      else
        bnext[v] = w;
      bprev[w] = v;
    }
  }
  const int64_t edges = int64_t(boundary_edges + paired / 2);
  const int64_t euler = int64_t(V) - edges + int64_t(ts.size());
  if (euler != 1)
    fail.add("V - E + F = " + std::to_string(V) + " - " + std::to_string(edges) + " + " +
             std::to_string(ts.size()) + " = " + std::to_string(euler) +
             ", not 1 (holes or separate pieces)");

  // Boundary = convex hull of all mesh vertices, collinear hull points included, counter-clockwise.
  {
    std::vector<std::size_t> idx(V), hull;
    std::iota(idx.begin(), idx.end(), std::size_t(0));
    using HullTraits = CGAL::Convex_hull_traits_adapter_2<K, CGAL::Pointer_property_map<P2>::type>;
    CGAL::convex_hull_2(idx.begin(), idx.end(), std::back_inserter(hull),
                        HullTraits(CGAL::make_property_map(P)));
    const size_t h = hull.size();
    if (h < 3) {
      fail.add("the mesh has triangles but its vertices are all on one line");
    } else if (bnext[hull[0]] == kNone) {
      fail.add("convex hull " + vtx(mv, uint32_t(hull[0])) + " is not on the mesh boundary");
    } else {
      const uint32_t start = uint32_t(hull[0]);
      uint32_t cur = start;
      size_t j = 0;  // the boundary is on hull edge hull[j] -> hull[j + 1]
      uint64_t steps = 0;
      bool walked = true;
      do {
        const uint32_t next = bnext[cur];
        const uint32_t target = uint32_t(hull[(j + 1) % h]);
        if (next == kNone || ++steps > boundary_edges) {
          fail.add("the boundary is not a closed cycle through " + vtx(mv, cur));
          walked = false;
          break;
        }
        if (next == target) {
          ++j;
        } else if (CGAL::orientation(P[hull[j]], P[target], P[next]) != CGAL::COLLINEAR ||
                   !CGAL::collinear_are_strictly_ordered_along_line(P[cur], P[next], P[target])) {
          fail.add("boundary edge " + vtx(mv, cur) + " -> " + vtx(mv, next) +
                   " leaves the convex hull edge " + vtx(mv, uint32_t(hull[j])) + " -> " + vtx(mv, target));
          walked = false;
          break;
        }
        cur = next;
      } while (cur != start);
      if (walked && j != h)
        fail.add("the boundary cycle passes " + std::to_string(j) + " of the " + std::to_string(h) +
                 " convex hull vertices in order");
      if (walked && steps != boundary_edges)
        fail.add("the hull cycle has " + std::to_string(steps) + " edges but the mesh has " +
                 std::to_string(boundary_edges) + " boundary edges (a hole or a separate piece)");
    }
  }

  // Constraints: each a path of mesh edges from a to b through vertices on the segment (exactly, or Steiner
  // vertices within rounding of it). The path's edges are the constrained edges.
  std::vector<uint8_t> constrained(he.size(), 0);
  std::vector<uint32_t> crossings(V, 0);  // constraint paths through each non-input vertex
  for (size_t c = 0; c < prepared.constraints.size(); ++c) {
    const uint32_t a = prepared.constraints[c][0], b = prepared.constraints[c][1];
    if (a >= mesh_of.size() || b >= mesh_of.size()) {
      fail.add("constraint " + std::to_string(c) + " (" + std::to_string(a) + ", " + std::to_string(b) +
               ") has a vertex index out of range");
      continue;
    }
    const uint32_t A = mesh_of[a], B = mesh_of[b];
    if (A == kNone || B == kNone) continue;  // already reported
    const P2 &pa = P[A], &pb = P[B];
    const double ux = pb.x() - pa.x(), uy = pb.y() - pa.y();
    const double len2 = ux * ux + uy * uy, len = std::sqrt(len2);
    const double mag = std::max({std::abs(pa.x()), std::abs(pa.y()), std::abs(pb.x()), std::abs(pb.y())});
    const double tol = 1e-9 * len + 8 * DBL_EPSILON * mag;
    auto on_segment = [&](uint32_t w) {
      if (is_input[w])
        return CGAL::orientation(pa, pb, P[w]) == CGAL::COLLINEAR &&
               CGAL::collinear_are_strictly_ordered_along_line(pa, P[w], pb);
      const double wx = P[w].x() - pa.x(), wy = P[w].y() - pa.y();
      const double along = wx * ux + wy * uy;
      return std::abs(wx * uy - wy * ux) <= tol * len && along > 0 && along < len2;
    };
    uint32_t cur = A;
    for (uint32_t steps = 0; cur != B; ++steps) {
      uint32_t best = kNone, best_he = kNone;
      double best_along = HUGE_VAL;
      auto consider = [&](uint32_t w, uint32_t h) {
        if (w == B) {
          best = w, best_he = h, best_along = -HUGE_VAL;
          return;
        }
        const double along = (P[w].x() - P[cur].x()) * ux + (P[w].y() - P[cur].y()) * uy;
        if (along > 0 && along < best_along && on_segment(w)) best = w, best_he = h, best_along = along;
      };
      for (uint32_t h = first[cur]; h < first[cur + 1]; ++h) consider(he[h].to, h);
      if (bprev[cur] != kNone) consider(bprev[cur], find_half_edge(bprev[cur], cur));
      if (best == kNone || steps > V) {
        fail.add("constraint " + std::to_string(c) + " from " + vtx(mv, A) + " to " + vtx(mv, B) +
                 " is not covered by mesh edges: no edge along it leaves " + vtx(mv, cur));
        break;
      }
      if (best_he != kNone) {
        constrained[best_he] = 1;
        if (twin[best_he] != kNone) constrained[twin[best_he]] = 1;
      }
      if (best != B && !is_input[best]) ++crossings[best];
      cur = best;
    }
  }
  for (uint32_t v = 0; v < V; ++v) {
    if (is_input[v]) continue;
    ++report.steiner_vertices;
    if (crossings[v] < 2)
      fail.add(vtx(mv, v) + " is not an input vertex and not a crossing of two constraints (on " +
               std::to_string(crossings[v]) + " constraint paths)");
  }

  // Locally Delaunay: every interior edge not on a constraint path, under CGAL's perturbed incircle test.
  CGAL::Triangulation_2<K> predicates;
  for (uint32_t v = 0; v < V; ++v)
    for (uint32_t h = first[v]; h < first[v + 1]; ++h) {
      const uint32_t w = he[h].to;
      if (constrained[h] && (twin[h] == kNone || v < w)) {
        ++report.constrained_edges;
        if (constrained_edges) constrained_edges->push_back({std::min(v, w), std::max(v, w)});
      }
      if (twin[h] == kNone || w < v || constrained[h]) continue;
      const uint32_t c = he[h].opp, d = he[twin[h]].opp;
      const CGAL::Oriented_side s = predicates.side_of_oriented_circle(P[v], P[w], P[c], P[d], true);
      if (s != CGAL::ON_NEGATIVE_SIDE)
        fail.add("edge " + std::to_string(v) + "-" + std::to_string(w) +
                 " is not locally Delaunay: " + vtx(mv, d) + " is inside the circumcircle of " +
                 tri(ts, he[h].tri) + " (" + vtx(mv, v) + ", " + vtx(mv, w) + ", " + vtx(mv, c) + ")");
    }
  fail.finish();
  if (constrained_edges) std::sort(constrained_edges->begin(), constrained_edges->end());
  return report;
}

}  // namespace cdtgpu
