// The CPU reference backend: CGAL's constrained Delaunay triangulation, the oracle of every GPU result.
#pragma once
#include "core/model.hpp"
#include "core/prepare.hpp"
#include "core/triangle_spans.hpp"

namespace cdtgpu {

struct CdtResult {
  Mesh mesh;                  // canonical order
  // Instead of mesh.triangles (then empty), where the caller asked a tiled run for them so
  // (TileOptions::in_runs): the canonical order left in the tiles' runs, for a writer. gather_triangles() makes
  // them mesh.triangles.
  OrderedRuns in_runs;
  uint64_t steiner_points = 0;  // vertices created where constraints cross
};

// mesh.triangles from in_runs, where they are there.
inline void gather_triangles(CdtResult& r) {
  if (!r.in_runs.empty()) r.mesh.triangles = std::move(r.in_runs).take();
  r.in_runs = OrderedRuns();
}

// CDT of prepared.vertices with every constraint segment, by the rules of docs/rules.md: constraints through
// other vertices are split there; crossing constraints get a Steiner vertex at the crossing (exact intersection,
// rounded to double), its z interpolated along the lower-indexed constraint (resolve_if_needed, then
// cdt_of_graph). Fewer than 3 vertices, or all collinear: no triangles.
CdtResult triangulate_cgal(const PreparedInput& prepared);

// The CDT of a planar straight-line graph (segments meet only at shared endpoints, none holds a vertex inside:
// what resolve_constraints makes), with CGAL's plain Constrained_Delaunay_triangulation_2, which refuses a
// crossing instead of constructing it. Counter-clockwise triangles in CGAL's face order; the same triangles as
// triangulate_cgal on the input the graph was resolved from. Fewer than 3 vertices or all collinear: none.
// `neighbours`, when given: 3 per triangle, [3i + k] the triangle across its edge from vertex k to vertex k + 1,
// or UINT32_MAX on the hull.
Triangles cdt_of_graph(const Points& vertices, const std::vector<Edge>& segments,
                                   std::vector<uint32_t>* neighbours = nullptr);

}  // namespace cdtgpu
