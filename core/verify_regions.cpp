// verify_regions: the reference CDT, a ray-parity inside test per triangle, the --max-edge trimming by a flood
// over the reference's own edge list, and a comparison of triangle sets. Cost: the CDT, then per triangle the region segments of one horizontal band (segments are listed in
// every band their y range meets).
#include "core/verify_regions.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;
using XP2 = CGAL::Exact_predicates_exact_constructions_kernel::Point_2;  // exact coordinates
using Corners = std::array<std::array<double, 3>, 3>;  // (x, y, z) of the corners, sorted by (x, y)

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

Corners corners(const Mesh& m, const Triangle& t) {
  Corners c;
  for (int k = 0; k < 3; ++k) c[k] = {m.vertices[t[k]].x, m.vertices[t[k]].y, m.vertices[t[k]].z};
  std::sort(c.begin(), c.end());
  return c;
}

std::string describe(const Corners& c) {
  std::string s = "triangle";
  for (int k = 0; k < 3; ++k) s += (k ? ", (" : " (") + num(c[k][0]) + ", " + num(c[k][1]) + ")";
  return s;
}

// Region segments bucketed into horizontal bands, for the ray-parity test.
class Rays {
 public:
  Rays(std::vector<std::array<P2, 2>> segs) : segs_(std::move(segs)) {
    if (segs_.empty()) return;
    y0_ = HUGE_VAL;
    double y1 = -HUGE_VAL;
    for (const auto& s : segs_)
      for (const P2& p : s) y0_ = std::min(y0_, p.y()), y1 = std::max(y1, p.y());
    bands_ = uint32_t(std::clamp<double>(double(segs_.size()) / 4, 1, 65536));
    h_ = std::max((y1 - y0_) / bands_, 1e-300);
    list_.resize(bands_);
    for (uint32_t i = 0; i < segs_.size(); ++i) {
      const uint32_t b0 = band(std::min(segs_[i][0].y(), segs_[i][1].y()));
      const uint32_t b1 = band(std::max(segs_[i][0].y(), segs_[i][1].y()));
      for (uint32_t b = b0; b <= b1; ++b) list_[b].push_back(i);
    }
  }

  // Parity of the segments crossed by the ray from c to +x; c is on none of them. XP2: a point with exact
  // coordinates (a sliver's centroid, where no point inside it has double ones).
  template <class Point>
  bool odd(const Point& c) const {
    if (segs_.empty()) return false;
    bool inside = false;
    for (uint32_t i : list_[band(CGAL::to_double(c.y()))]) {  // rounding keeps it in a band of c's segments
      const Point p(segs_[i][0].x(), segs_[i][0].y()), q(segs_[i][1].x(), segs_[i][1].y());
      if ((p.y() > c.y()) == (q.y() > c.y())) continue;
      // Upward p -> q: crossed when c is left of it; downward: when c is right of it.
      const CGAL::Orientation o = CGAL::orientation(p, q, c);
      inside ^= q.y() > p.y() ? o == CGAL::LEFT_TURN : o == CGAL::RIGHT_TURN;
    }
    return inside;
  }

 private:
  uint32_t band(double y) const {
    return uint32_t(std::clamp(std::floor((y - y0_) / h_), 0.0, double(bands_ - 1)));
  }
  std::vector<std::array<P2, 2>> segs_;
  std::vector<std::vector<uint32_t>> list_;
  double y0_ = 0, h_ = 1;
  uint32_t bands_ = 1;
};

// A point strictly inside the triangle, or false for a degenerate one.
bool interior_point(const P2& a, const P2& b, const P2& c, P2& out) {
  static const double w[4][3] = {{1. / 3, 1. / 3, 1. / 3}, {.5, .25, .25}, {.25, .5, .25}, {.25, .25, .5}};
  for (const auto& [u, v, t] : w) {
    out = P2(u * a.x() + v * b.x() + t * c.x(), u * a.y() + v * b.y() + t * c.y());
    if (CGAL::orientation(a, b, out) == CGAL::LEFT_TURN && CGAL::orientation(b, c, out) == CGAL::LEFT_TURN &&
        CGAL::orientation(c, a, out) == CGAL::LEFT_TURN)
      return true;
  }
  return false;
}

// The reference CDT's triangles that --max-edge trims: reached from beyond the hull across edges longer than
// max_edge that lie on no constraint. Its own adjacency (a sorted edge list), independent of apply_regions.
std::vector<uint8_t> trimmed_reference(const Mesh& m, const std::vector<Edge>& constrained, double max_edge) {
  struct Side {
    Edge e;
    uint32_t t;
    bool operator<(const Side& o) const { return e != o.e ? e < o.e : t < o.t; }
  };
  std::vector<Side> sides;
  for (uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      sides.push_back({{std::min(a, b), std::max(a, b)}, t});
    }
  std::sort(sides.begin(), sides.end());
  auto long_open = [&](const Edge& e) {
    const Point3 &a = m.vertices[e[0]], &b = m.vertices[e[1]];
    const double dx = b.x - a.x, dy = b.y - a.y;  // the rule's own comparison, squared in doubles
    return dx * dx + dy * dy > max_edge * max_edge &&
           !std::binary_search(constrained.begin(), constrained.end(), e);
  };
  std::vector<std::vector<uint32_t>> across(m.triangles.size());  // neighbours across long open edges
  std::vector<uint8_t> gone(m.triangles.size(), 0);
  std::vector<uint32_t> stack;
  for (size_t i = 0; i < sides.size();) {
    size_t j = i;
    while (j < sides.size() && sides[j].e == sides[i].e) ++j;
    if (long_open(sides[i].e)) {
      if (j - i == 1 && !gone[sides[i].t]) {  // a hull edge
        gone[sides[i].t] = 1;
        stack.push_back(sides[i].t);
      }
      if (j - i == 2) {
        across[sides[i].t].push_back(sides[i + 1].t);
        across[sides[i + 1].t].push_back(sides[i].t);
      }
    }
    i = j;
  }
  while (!stack.empty()) {
    const uint32_t t = stack.back();
    stack.pop_back();
    for (uint32_t n : across[t])
      if (!gone[n]) gone[n] = 1, stack.push_back(n);
  }
  return gone;
}

}  // namespace

VerifyReport verify_regions(const Mesh& mesh, const PreparedInput& prepared, const RegionRules& rules,
                            size_t max_failures) {
  // Only inside closed rings is a ray's parity the nesting level.
  if (const OpenEnds open = open_region_ends(prepared, rules); open.count)
    throw UsageError("verify: the " + open_ends_text(prepared, open) + ": a region that does not close leaks " +
                     "(docs/rules.md, \"Regions\"), which verify does not check; close the rings");
  const CdtResult full = triangulate_cgal(prepared);
  std::vector<Edge> constrained;
  VerifyReport report = verify_mesh(full.mesh, prepared, max_failures, &constrained);
  if (!report.ok()) {
    for (std::string& f : report.failures) f = "reference CDT: " + f;
    return report;
  }
  auto fail = [&](const std::string& s) {
    if (report.failures.size() < max_failures) report.failures.push_back(s);
  };

  std::vector<std::array<P2, 2>> segs;
  for (size_t c = 0; c < prepared.constraints.size(); ++c)
    if (c < rules.region_edge.size() && rules.region_edge[c]) {
      const Point3 &a = prepared.vertices[prepared.constraints[c][0]],
                   &b = prepared.vertices[prepared.constraints[c][1]];
      segs.push_back({P2(a.x, a.y), P2(b.x, b.y)});
    }
  const Rays rays(std::move(segs));

  // The domain's triangles, each counted: +1 when expected, -1 when in the mesh.
  std::map<Corners, int> count;
  const std::vector<uint8_t> gone = rules.max_edge > 0
                                        ? trimmed_reference(full.mesh, constrained, rules.max_edge)
                                        : std::vector<uint8_t>(full.mesh.triangles.size(), 0);
  for (size_t i = 0; i < full.mesh.triangles.size(); ++i) {
    const Triangle& t = full.mesh.triangles[i];
    if (gone[i]) continue;
    const Point3 &a = full.mesh.vertices[t[0]], &b = full.mesh.vertices[t[1]], &c = full.mesh.vertices[t[2]];
    P2 inner;
    // A sliver with no point strictly inside in doubles: its centroid, exactly.
    const bool odd = interior_point(P2(a.x, a.y), P2(b.x, b.y), P2(c.x, c.y), inner)
                         ? rays.odd(inner)
                         : rays.odd(CGAL::centroid(XP2(a.x, a.y), XP2(b.x, b.y), XP2(c.x, c.y)));
    if (odd != rules.outside_kept) ++count[corners(full.mesh, t)];
  }
  for (const Triangle& t : mesh.triangles) {
    if (t[0] >= mesh.vertices.size() || t[1] >= mesh.vertices.size() || t[2] >= mesh.vertices.size()) {
      fail("a triangle has a vertex index out of range");
      return report;
    }
    --count[corners(mesh, t)];
  }
  for (const auto& [c, n] : count) {
    if (n > 0) fail(describe(c) + " of the domain is missing from the mesh");
    if (n < 0)
      fail(describe(c) +
           " is in the mesh but not a triangle of the CDT inside the domain (or has another z)");
  }
  std::vector<uint8_t> used(mesh.vertices.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) used[v] = 1;
  for (size_t v = 0; v < used.size(); ++v)
    if (!used[v])
      fail("vertex " + std::to_string(v) + " (" + num(mesh.vertices[v].x) + ", " + num(mesh.vertices[v].y) +
           ") is in no triangle (vertices outside the domain are dropped)");
  return report;
}

}  // namespace cdtgpu
