// apply_regions: boundaries, holes and max-edge trimming over a finished CDT. Cost: O(T): per-vertex lists
// of the 3T half-edges (counting sort) and their twins, one walk per constraint along mesh edges, one flood
// fill, one compaction.
//
// The constrained mesh edges are found the way verify.cpp finds them: from one end of a constraint, step to
// the neighbour that lies on the segment (exact orientation for input vertices; within rounding for Steiner
// vertices, which are rounded crossings and generally just off the segment) and is nearest along it.
#include "core/regions.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint8_t kConstrained = 1, kRegion = 2;

uint64_t key(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

bool xy_less(const Point3& a, const Point3& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; }

// Index of the vertex at (x, y) in vertices sorted by (x, y), or kNone.
uint32_t find_vertex(const std::vector<Point3>& vs, const Point3& p) {
  auto it = std::lower_bound(vs.begin(), vs.end(), p, xy_less);
  return it != vs.end() && it->x == p.x && it->y == p.y ? uint32_t(it - vs.begin()) : kNone;
}

// Half-edge h = 3 t + k runs from triangle t's vertex k to vertex k + 1.
struct HalfEdges {
  std::vector<uint32_t> twin;        // kNone on the hull
  std::vector<uint32_t> first, out;  // CSR: half-edges leaving each vertex
  std::vector<uint32_t> bprev_edge;  // per vertex: the hull half-edge ending there, or kNone
};

HalfEdges half_edges(const Mesh& mesh) {
  const std::vector<Triangle>& ts = mesh.triangles;
  const uint32_t V = uint32_t(mesh.vertices.size());
  const size_t H = ts.size() * 3;
  auto from = [&](size_t h) { return ts[h / 3][h % 3]; };
  auto to = [&](size_t h) { return ts[h / 3][(h % 3 + 1) % 3]; };
  HalfEdges e;
  // Half-edges leaving each vertex (counting sort), then each one's twin among those leaving its target
  // (about six): no sort.
  e.first.assign(size_t(V) + 1, 0);
  for (size_t h = 0; h < H; ++h) ++e.first[from(h) + 1];
  for (uint32_t v = 0; v < V; ++v) e.first[v + 1] += e.first[v];
  e.out.resize(H);
  std::vector<uint32_t> cursor(e.first.begin(), e.first.end() - 1);
  for (size_t h = 0; h < H; ++h) e.out[cursor[from(h)]++] = uint32_t(h);
  cursor = {};
  e.twin.assign(H, kNone);
  e.bprev_edge.assign(V, kNone);
  for (size_t h = 0; h < H; ++h) {
    const uint32_t a = from(h), b = to(h);
    for (uint32_t i = e.first[b]; i < e.first[b + 1]; ++i)
      if (to(e.out[i]) == a) {
        e.twin[h] = e.out[i];
        break;
      }
    if (e.twin[h] == kNone) e.bprev_edge[b] = uint32_t(h);
  }
  return e;
}

uint32_t from_of(const Mesh& m, uint32_t h) { return m.triangles[h / 3][h % 3]; }
uint32_t to_of(const Mesh& m, uint32_t h) { return m.triangles[h / 3][(h % 3 + 1) % 3]; }

// Marks the mesh edges along every constraint: kConstrained, plus kRegion for region edges.
void mark_constraints(const Mesh& mesh, const PreparedInput& prepared, const std::vector<uint8_t>& region,
                      const HalfEdges& e, std::vector<uint8_t>& flag) {
  const std::vector<Point3>& mv = mesh.vertices;
  const uint32_t V = uint32_t(mv.size());
  std::vector<P2> P;
  P.reserve(V);
  for (const Point3& p : mv) P.emplace_back(p.x, p.y);
  std::vector<uint8_t> is_input(V, 0);
  // Both vertex lists are sorted by (x, y): one merge pass finds every input vertex in the mesh.
  std::vector<uint32_t> mesh_of(prepared.vertices.size());
  uint32_t m = 0;
  for (size_t i = 0; i < prepared.vertices.size(); ++i) {
    const Point3& p = prepared.vertices[i];
    while (m < V && xy_less(mv[m], p)) ++m;
    if (m == V || mv[m].x != p.x || mv[m].y != p.y)
      throw std::logic_error("regions: input vertex " + std::to_string(i) + " is not in the mesh");
    mesh_of[i] = m;
    is_input[m] = 1;
  }
  for (size_t c = 0; c < prepared.constraints.size(); ++c) {
    // Region edges toggle: a mesh edge covered by two region segments (collinear overlaps) is crossed twice.
    const uint8_t toggle = c < region.size() && region[c] ? kRegion : 0;
    const uint32_t A = mesh_of[prepared.constraints[c][0]], B = mesh_of[prepared.constraints[c][1]];
    const P2 &pa = P[A], &pb = P[B];
    const double ux = pb.x() - pa.x(), uy = pb.y() - pa.y();
    const double len2 = ux * ux + uy * uy, len = std::sqrt(len2);
    const double mag = std::max({std::abs(pa.x()), std::abs(pa.y()), std::abs(pb.x()), std::abs(pb.y())});
    const double tol = 1e-9 * len + 8 * DBL_EPSILON * mag;  // verify.cpp's tolerance for Steiner vertices
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
        if (best_along == -HUGE_VAL) return;
        if (w == B) {
          best = w, best_he = h, best_along = -HUGE_VAL;
          return;
        }
        const double along = (P[w].x() - P[cur].x()) * ux + (P[w].y() - P[cur].y()) * uy;
        if (along > 0 && along < best_along && on_segment(w)) best = w, best_he = h, best_along = along;
      };
      for (uint32_t i = e.first[cur]; i < e.first[cur + 1]; ++i) consider(to_of(mesh, e.out[i]), e.out[i]);
      if (e.bprev_edge[cur] != kNone) consider(from_of(mesh, e.bprev_edge[cur]), e.bprev_edge[cur]);
      if (best == kNone || steps > V)
        throw std::logic_error("regions: constraint " + std::to_string(c) +
                               " is not covered by mesh edges (the mesh is not the CDT of its input)");
      flag[best_he] = uint8_t((flag[best_he] | kConstrained) ^ toggle);
      if (e.twin[best_he] != kNone) flag[e.twin[best_he]] = flag[best_he];
      cur = best;
    }
  }
}

// Nesting level of every triangle: 0 for those reached from beyond the hull without crossing a region edge,
// +1 for each region edge crossed (breadth first, as CGAL's mark_domains).
std::vector<uint32_t> nesting_levels(const Mesh& mesh, const HalfEdges& e, const std::vector<uint8_t>& flag) {
  const size_t T = mesh.triangles.size();
  std::vector<uint32_t> level(T, kNone);
  std::vector<std::vector<uint32_t>> pending(2);
  for (size_t h = 0; h < 3 * T; ++h)
    if (e.twin[h] == kNone) pending[(flag[h] & kRegion) ? 1 : 0].push_back(uint32_t(h / 3));
  for (uint32_t L = 0; L < pending.size(); ++L) {
    std::vector<uint32_t> stack = std::move(pending[L]);
    while (!stack.empty()) {
      const uint32_t t = stack.back();
      stack.pop_back();
      if (level[t] != kNone) continue;
      level[t] = L;
      for (uint32_t h = 3 * t; h < 3 * t + 3; ++h) {
        const uint32_t n = e.twin[h];
        if (n == kNone || level[n / 3] != kNone) continue;
        if (flag[h] & kRegion) {
          if (pending.size() < L + 2) pending.resize(L + 2);
          pending[L + 1].push_back(n / 3);
        } else {
          stack.push_back(n / 3);
        }
      }
    }
  }
  return level;
}

// Triangles reached from beyond the hull across unconstrained edges longer than max_edge.
std::vector<uint8_t> trimmed(const Mesh& mesh, const HalfEdges& e, const std::vector<uint8_t>& flag,
                             double max_edge) {
  const size_t T = mesh.triangles.size();
  const double limit2 = max_edge * max_edge;
  auto long_open = [&](uint32_t h) {
    if (flag[h] & kConstrained) return false;
    const Point3 &a = mesh.vertices[from_of(mesh, h)], &b = mesh.vertices[to_of(mesh, h)];
    const double dx = b.x - a.x, dy = b.y - a.y;
    return dx * dx + dy * dy > limit2;
  };
  std::vector<uint8_t> gone(T, 0);
  std::vector<uint32_t> stack;
  for (uint32_t h = 0; h < 3 * T; ++h)
    if (e.twin[h] == kNone && !gone[h / 3] && long_open(h)) {
      gone[h / 3] = 1;
      stack.push_back(h / 3);
    }
  while (!stack.empty()) {
    const uint32_t t = stack.back();
    stack.pop_back();
    for (uint32_t h = 3 * t; h < 3 * t + 3; ++h) {
      const uint32_t n = e.twin[h];
      if (n == kNone || gone[n / 3] || !long_open(h)) continue;
      gone[n / 3] = 1;
      stack.push_back(n / 3);
    }
  }
  return gone;
}

}  // namespace

std::vector<uint8_t> region_constraints(const PreparedInput& prepared, const std::vector<Polyline>& rings) {
  std::vector<uint64_t> segs;
  for (const Polyline& l : rings) {
    const size_t n = l.points.size();
    const size_t count = n < 2 ? 0 : (l.closed && n >= 3 ? n : n - 1);
    for (size_t k = 0; k < count; ++k) {
      uint32_t a = find_vertex(prepared.vertices, l.points[k]);
      uint32_t b = find_vertex(prepared.vertices, l.points[(k + 1) % n]);
      if (a == kNone || b == kNone || a == b) continue;
      if (a > b) std::swap(a, b);
      segs.push_back(key(a, b));
    }
  }
  std::sort(segs.begin(), segs.end());
  // A segment given by two rings (adjacent parcels, a lake on the boundary) is crossed twice: no region edge.
  std::vector<uint8_t> region(prepared.constraints.size(), 0);
  for (size_t c = 0; c < region.size(); ++c) {
    const uint64_t k = key(prepared.constraints[c][0], prepared.constraints[c][1]);
    region[c] =
        (std::upper_bound(segs.begin(), segs.end(), k) - std::lower_bound(segs.begin(), segs.end(), k)) % 2;
  }
  return region;
}

RegionRules region_rules(const InputSet& in, const std::vector<InputPart>& parts,
                         const PreparedInput& prepared, double max_edge) {
  std::vector<Polyline> rings;
  bool boundary = false;
  for (const InputPart& part : parts) {
    if (part.role != Role::boundary && part.role != Role::hole) continue;
    for (size_t i = part.lines_begin; i < part.lines_end; ++i) rings.push_back(in.lines[i]);
    boundary |= part.role == Role::boundary && part.lines_end > part.lines_begin;
  }
  RegionRules rules;
  if (!rings.empty()) rules.region_edge = region_constraints(prepared, rings);
  rules.outside_kept = !boundary;
  rules.max_edge = max_edge;
  return rules;
}

RegionStats apply_regions(Mesh& mesh, const PreparedInput& prepared, const RegionRules& rules) {
  RegionStats stats;
  const size_t T = mesh.triangles.size();
  const bool regions =
      std::find(rules.region_edge.begin(), rules.region_edge.end(), 1) != rules.region_edge.end();
  if (T == 0 || (!regions && rules.max_edge <= 0)) return stats;
  const HalfEdges e = half_edges(mesh);
  std::vector<uint8_t> flag(3 * T, 0);
  mark_constraints(mesh, prepared, rules.region_edge, e, flag);

  std::vector<uint8_t> keep(T, 1);
  if (regions) {
    const std::vector<uint32_t> level = nesting_levels(mesh, e, flag);
    for (size_t t = 0; t < T; ++t) {
      const bool odd = level[t] % 2 == 1;  // every triangle is reached: the mesh is connected
      keep[t] = odd != rules.outside_kept;
      stats.triangles_outside += !keep[t];
    }
  }
  if (rules.max_edge > 0) {
    const std::vector<uint8_t> gone = trimmed(mesh, e, flag, rules.max_edge);
    for (size_t t = 0; t < T; ++t)
      if (gone[t] && keep[t]) {
        keep[t] = 0;
        ++stats.triangles_trimmed;
      }
  }

  // Compaction: kept triangles, then the vertices still used. The renumbering keeps the order of vertices,
  // so triangles stay sorted and start at their smallest index: the mesh stays canonical.
  std::vector<Triangle> kept;
  kept.reserve(T - stats.triangles_outside - stats.triangles_trimmed);
  std::vector<uint32_t> renumber(mesh.vertices.size(), kNone);
  for (size_t t = 0; t < T; ++t)
    if (keep[t]) {
      kept.push_back(mesh.triangles[t]);
      for (uint32_t v : mesh.triangles[t]) renumber[v] = 0;
    }
  std::vector<Point3> vertices;
  for (size_t v = 0; v < renumber.size(); ++v)
    if (renumber[v] == 0) {
      renumber[v] = uint32_t(vertices.size());
      vertices.push_back(mesh.vertices[v]);
    }
  stats.vertices_removed = mesh.vertices.size() - vertices.size();
  for (Triangle& t : kept)
    for (uint32_t& v : t) v = renumber[v];
  mesh.vertices = std::move(vertices);
  mesh.triangles = std::move(kept);
  return stats;
}

}  // namespace cdtgpu
