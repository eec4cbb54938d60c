// triangulate_cgal and cdt_of_graph: CGAL's Constrained_Delaunay_triangulation_2 (Epick) of a planar graph.
// Crossing constraints are resolved first (core/resolve: the rules of docs/rules.md), not by CGAL: its
// Constrained_triangulation_plus_2 with rounded crossings crashed, looped or split differently on lattice
// inputs (tests/cgal_plus.hpp keeps it as the tests' independent check of the resolve). Points go in spatially
// sorted with a hint (what CGAL's range insert does), constraints by vertex handle. Ties between co-circular
// points are broken by CGAL itself: its Delaunay flips call side_of_oriented_circle(..., perturb = true), the
// symbolic perturbation that verify.cpp and the GPU backend use too, so the triangulation is unique.
#include "core/cdt_cgal.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>

#include <numeric>

#include "core/canonical.hpp"
#include "core/resolve.hpp"

namespace cdtgpu {

namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;

// Inserts the vertices as CGAL's range insert does (Hilbert-sorted, each with the last one's face as hint);
// `set_index(handle, i)` records vertex i's index on its handle. Returns the handle of each vertex.
template <class Tri, class SetIndex>
std::vector<typename Tri::Vertex_handle> insert_points(Tri& cdt, const Points& vertices,
                                                       SetIndex set_index) {
  std::vector<Epick::Point_2> points;
  points.reserve(vertices.size());
  for (const Point3& p : vertices) points.emplace_back(p.x, p.y);
  std::vector<std::size_t> order(points.size());  // size_t: the key type of CGAL's pointer property map
  std::iota(order.begin(), order.end(), std::size_t(0));
  using SortTraits =
      CGAL::Spatial_sort_traits_adapter_2<Epick, CGAL::Pointer_property_map<Epick::Point_2>::type>;
  // Splits at the middle of each box, not at the median (no selection a level): a 16-thread host's 2M + 500K
  // CPU tiles took 630 ms against 666 (medians of 9); the single run is unchanged. Any order gives the same CDT.
  // (It reads the first point for the box, so not on an empty list.)
  if (!order.empty())
    CGAL::spatial_sort(order.begin(), order.end(), SortTraits(CGAL::make_property_map(points)),
                       CGAL::Hilbert_sort_middle_policy());
  std::vector<typename Tri::Vertex_handle> handle(points.size());
  typename Tri::Face_handle hint;
  for (std::size_t i : order) {
    handle[i] = cdt.insert(points[i], hint);
    set_index(handle[i], uint32_t(i));
    hint = handle[i]->face();
  }
  return handle;
}

}  // namespace

CdtResult triangulate_cgal(const PreparedInput& prepared) {
  // The rules' planar graph (core/resolve); an input with nothing to split is its own.
  ResolvedInput r = resolve_if_needed(prepared);
  CdtResult result;
  result.steiner_points = r.steiner_points;
  result.mesh.triangles = r.unchanged ? cdt_of_graph(prepared.vertices, prepared.constraints)
                                      : cdt_of_graph(r.vertices, r.constraints);
  canonicalize_triangles(result.mesh.triangles);
  result.mesh.vertices = r.unchanged ? prepared.vertices : std::move(r.vertices);
  return result;
}

Triangles cdt_of_graph(const Points& vertices, const std::vector<Edge>& segments,
                                   std::vector<uint32_t>* neighbours) {
  using GVb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, Epick>;
  struct FaceIndex {
    uint32_t i = UINT32_MAX;  // finite faces get their position in the output
  };
  using GFb = CGAL::Constrained_triangulation_face_base_2<Epick, CGAL::Triangulation_face_base_with_info_2<FaceIndex, Epick>>;
  using GTds = CGAL::Triangulation_data_structure_2<GVb, GFb>;
  using GraphCdt = CGAL::Constrained_Delaunay_triangulation_2<Epick, GTds, CGAL::No_constraint_intersection_tag>;
  GraphCdt cdt;
  const std::vector<GraphCdt::Vertex_handle> handle =
      insert_points(cdt, vertices, [](GraphCdt::Vertex_handle v, uint32_t i) { v->info() = i; });
  for (const Edge& e : segments) cdt.insert_constraint(handle[e[0]], handle[e[1]]);
  Triangles triangles;
  if (cdt.dimension() != 2) return triangles;
  triangles.reserve(cdt.number_of_faces());
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    f->info().i = uint32_t(triangles.size());
    triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  }
  if (neighbours) {
    neighbours->resize(3 * triangles.size());
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
      for (int k = 0; k < 3; ++k)  // the edge from vertex k to k + 1 is opposite vertex k + 2
        (*neighbours)[3 * f->info().i + k] = f->neighbor((k + 2) % 3)->info().i;
  }
  return triangles;
}

}  // namespace cdtgpu
