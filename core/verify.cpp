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
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "core/resolve.hpp"

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

// resolve_if_needed of `prepared` in prepare's order (verify's callers may hand any): vertices sorted by (x, y)
// and unique, constraints (a < b) sorted and unique. The resolve takes constraints in any order, but a Steiner
// vertex's z follows the lowest-indexed constraint through it, from its first end.
ResolvedInput rules_graph(const PreparedInput& prepared) {
  const Points& v = prepared.vertices;
  auto less = [](const Point3& a, const Point3& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; };
  bool sorted = std::adjacent_find(v.begin(), v.end(), [&](const Point3& a, const Point3& b) {
                  return !less(a, b);
                }) == v.end();
  for (const Edge& e : prepared.constraints) sorted = sorted && e[0] < e[1];
  sorted = sorted && std::is_sorted(prepared.constraints.begin(), prepared.constraints.end());
  if (sorted) return resolve_if_needed(prepared);
  PreparedInput p;
  std::vector<uint32_t> order(v.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return less(v[a], v[b]); });
  std::vector<uint32_t> id(v.size());
  for (uint32_t i : order) {
    if (p.vertices.empty() || less(p.vertices.back(), v[i])) p.vertices.push_back(v[i]);
    id[i] = uint32_t(p.vertices.size() - 1);
  }
  for (const Edge& e : prepared.constraints) {
    const uint32_t a = id[e[0]], b = id[e[1]];
    if (a != b) p.constraints.push_back({std::min(a, b), std::max(a, b)});
  }
  std::sort(p.constraints.begin(), p.constraints.end());
  p.constraints.erase(std::unique(p.constraints.begin(), p.constraints.end()), p.constraints.end());
  return resolve_constraints(p);
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

  // Constraints: the rules' planar graph (docs/rules.md, core/resolve): each constraint split at the vertices
  // exactly on it and at its crossings, whose Steiner vertices are the exact crossings rounded to doubles. Each
  // piece must be a mesh edge, each Steiner vertex in the mesh with the rules' z, and no other vertex added.
  // (Following each constraint through the mesh's vertices near it instead was ambiguous where rounded crossings
  // cascade: two Steiner vertices 7e-12 apart beside one constraint at UTM coordinates.)
  std::vector<uint8_t> constrained(he.size(), 0);
  bool indices_ok = true;
  for (size_t c = 0; c < prepared.constraints.size(); ++c) {
    const uint32_t a = prepared.constraints[c][0], b = prepared.constraints[c][1];
    if (a >= prepared.vertices.size() || b >= prepared.vertices.size() || a == b) {
      fail.add("constraint " + std::to_string(c) + " (" + std::to_string(a) + ", " + std::to_string(b) +
               ") has a vertex index out of range or twice");
      indices_ok = false;
    }
  }
  const ResolvedInput graph = indices_ok ? rules_graph(prepared) : ResolvedInput{};
  const Points& gv = graph.unchanged ? prepared.vertices : graph.vertices;
  const std::vector<Edge>& pieces = graph.unchanged ? prepared.constraints : graph.constraints;
  std::vector<uint32_t> mesh_of_graph(gv.size(), kNone);
  std::vector<uint8_t> in_graph(V, 0);
  // Whether a graph vertex missing from the mesh is an input vertex (reported above): the inputs sorted only
  // when one is missing, not on every verify.
  std::vector<std::pair<double, double>> inputs;
  auto an_input = [&](const Point3& p) {
    if (inputs.empty()) {
      for (const Point3& q : prepared.vertices) inputs.push_back({q.x, q.y});
      std::sort(inputs.begin(), inputs.end());
    }
    return std::binary_search(inputs.begin(), inputs.end(), std::pair<double, double>(p.x, p.y));
  };
  for (uint32_t i = 0; i < gv.size(); ++i) {
    const Point3& p = gv[i];
    auto it = std::lower_bound(by_xy.begin(), by_xy.end(), p, [&](uint32_t a, const Point3& q) {
      return mv[a].x != q.x ? mv[a].x < q.x : mv[a].y < q.y;
    });
    if (it == by_xy.end() || mv[*it].x != p.x || mv[*it].y != p.y) {
      if (!an_input(p))
        fail.add("the Steiner vertex (" + num(p.x) + ", " + num(p.y) + ") where constraints cross is missing");
      continue;
    }
    mesh_of_graph[i] = *it;
    in_graph[*it] = 1;
    if (!is_input[*it] && mv[*it].z != p.z)
      fail.add("Steiner " + vtx(mv, *it) + " has z " + num(mv[*it].z) + " but the rules give " + num(p.z));
  }
  for (uint32_t v = 0; v < V; ++v) {
    if (is_input[v]) continue;
    ++report.steiner_vertices;
    if (!in_graph[v]) fail.add(vtx(mv, v) + " is not an input vertex and not a crossing of constraints");
  }
  for (const Edge& e : pieces) {
    const uint32_t a = mesh_of_graph[e[0]], b = mesh_of_graph[e[1]];
    if (a == kNone || b == kNone) continue;  // already reported
    uint32_t h = find_half_edge(a, b);
    if (h == kNone) h = find_half_edge(b, a);
    if (h == kNone) {
      fail.add("the constraint from " + vtx(mv, a) + " to " + vtx(mv, b) +
               " (a constraint split at its vertices and crossings) is not covered by mesh edges");
      continue;
    }
    constrained[h] = 1;
    if (twin[h] != kNone) constrained[twin[h]] = 1;
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
