// CGAL's own handling of crossing constraints, as the tests' independent check of core/resolve: its
// Constrained_triangulation_plus_2 (Exact_intersections_tag) with every crossing computed exactly and rounded to
// the nearest double. The product does not use it: on some inputs it crashes (segfaults and endless loops in
// CGAL 5.5.1 on lattice inputs with T-junctions beside rounded crossings) or splits constraints differently from
// the rules (docs/rules.md, tests/resolve_test.cpp). triangulate_cgal (core/cdt_cgal.hpp) resolves first.
#pragma once
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_plus_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <bit>
#include <cmath>
#include <limits>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"

namespace cdtgpu::cgal_plus {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;

// Rounds an exact rational to the nearest double (ties to even). to_double may be off by one ulp, so the
// neighbours are compared exactly.
inline double round_nearest(const CGAL::Exact_rational& q) {
  const double m = CGAL::to_double(q);
  double best = m;
  CGAL::Exact_rational best_err = CGAL::abs(q - CGAL::Exact_rational(m));
  for (double c : {std::nextafter(m, -HUGE_VAL), std::nextafter(m, HUGE_VAL)}) {
    if (!std::isfinite(c)) continue;
    const CGAL::Exact_rational err = CGAL::abs(q - CGAL::Exact_rational(c));
    if (err < best_err || (err == best_err && (std::bit_cast<uint64_t>(c) & 1) == 0)) {
      best = c;
      best_err = err;
    }
  }
  return best;
}

// Epick with one change: the crossing of two segments is computed exactly and rounded to the nearest double
// (Epick's own construction is a double formula). That makes a Steiner point a function of the two input
// segments alone, reproducible by any backend. CT_plus_2 with Exact_intersections_tag intersects the
// enclosing input constraints, not the sub-segments, so errors do not accumulate.
struct Traits : Epick {
  struct Intersect_2 : Epick::Intersect_2 {
    using Base = Epick::Intersect_2;
    using Base::operator();
    using Result =
        decltype(std::declval<Base>()(std::declval<Epick::Segment_2>(), std::declval<Epick::Segment_2>()));

    Result operator()(const Epick::Segment_2& s, const Epick::Segment_2& t) const {
      using Q = CGAL::Exact_rational;
      const Epick::Point_2 a = s.source(), b = s.target(), c = t.source(), d = t.target();
      const Q ax(a.x()), ay(a.y()), bx(b.x()), by(b.y()), cx(c.x()), cy(c.y()), dx(d.x()), dy(d.y());
      const Q den = (bx - ax) * (dy - cy) - (by - ay) * (dx - cx);
      // Parallel (collinear overlap) or not crossing: Epick's answer (CT_plus_2 only asks about crossings).
      if (CGAL::is_zero(den)) return Base::operator()(s, t);
      const Q u = ((cx - ax) * (dy - cy) - (cy - ay) * (dx - cx)) / den;
      const Q v = ((cx - ax) * (by - ay) - (cy - ay) * (bx - ax)) / den;
      if (u < 0 || u > 1 || v < 0 || v > 1) return Result();
      const Epick::Point_2 p(round_nearest(ax + u * (bx - ax)), round_nearest(ay + u * (by - ay)));
      return Result(typename Result::value_type(p));
    }
  };
  Intersect_2 intersect_2_object() const { return Intersect_2(); }
};

constexpr uint32_t kSteiner = std::numeric_limits<uint32_t>::max();
struct VertexInfo {
  uint32_t index = kSteiner;  // input vertex index; CGAL default-constructs Steiner vertices' info
};

using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexInfo, Traits>;
using Fb = CGAL::Constrained_triangulation_face_base_2<Traits>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Traits, Tds, CGAL::Exact_intersections_tag>;
using CdtPlus = CGAL::Constrained_triangulation_plus_2<Cdt>;

// CDT of prepared.vertices with every constraint: constraints through other vertices are split there, crossing
// ones get a Steiner vertex at the crossing (exact, rounded to double), its z interpolated along the
// lower-indexed constraint. Canonical. Points go in one by one, each with the last one's face as hint.
inline CdtResult triangulate(const PreparedInput& prepared) {
  const Points& in = prepared.vertices;
  const uint32_t n = uint32_t(in.size());
  CdtResult result;

  CdtPlus cdt;
  std::vector<CdtPlus::Vertex_handle> handle(n);
  CdtPlus::Face_handle hint;
  for (uint32_t i = 0; i < n; ++i) {
    handle[i] = cdt.insert(Epick::Point_2(in[i].x, in[i].y), hint);
    handle[i]->info().index = i;
    hint = handle[i]->face();
  }
  std::vector<CdtPlus::Constraint_id> ids;
  ids.reserve(prepared.constraints.size());
  for (const Edge& e : prepared.constraints) ids.push_back(cdt.insert_constraint(handle[e[0]], handle[e[1]]));

  // Steiner vertices: index after the input vertices, z along the lowest-indexed constraint through them.
  result.mesh.vertices = in;
  for (size_t c = 0; c < ids.size(); ++c) {
    if (ids[c] == CdtPlus::Constraint_id(nullptr)) continue;
    const Point3& a = in[prepared.constraints[c][0]];
    const Point3& b = in[prepared.constraints[c][1]];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    for (auto it = cdt.vertices_in_constraint_begin(ids[c]); it != cdt.vertices_in_constraint_end(ids[c]);
         ++it) {
      CdtPlus::Vertex_handle v = *it;
      if (v->info().index != kSteiner) continue;
      v->info().index = uint32_t(result.mesh.vertices.size());
      const double x = v->point().x(), y = v->point().y();
      const double t = len > 0 ? std::min(1.0, std::hypot(x - a.x, y - a.y) / len) : 0.0;
      result.mesh.vertices.push_back({x, y, a.z + t * (b.z - a.z)});
    }
  }
  // A Steiner vertex is on two constraints by construction; this catches one the hierarchy did not list.
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v)
    if (v->info().index == kSteiner) {
      v->info().index = uint32_t(result.mesh.vertices.size());
      result.mesh.vertices.push_back({v->point().x(), v->point().y(), 0.0});
    }
  result.steiner_points = result.mesh.vertices.size() - n;

  if (cdt.dimension() == 2) {
    result.mesh.triangles.reserve(cdt.number_of_faces());
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
      result.mesh.triangles.push_back(
          {f->vertex(0)->info().index, f->vertex(1)->info().index, f->vertex(2)->info().index});
  }
  canonicalize(result.mesh);
  return result;
}

}  // namespace cdtgpu::cgal_plus
