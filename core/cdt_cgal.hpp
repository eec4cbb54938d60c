// The CPU reference backend: CGAL's constrained Delaunay triangulation, the oracle of every GPU result.
#pragma once
#include "core/model.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

struct CdtResult {
  Mesh mesh;                  // canonical order
  uint64_t steiner_points = 0;  // vertices created where constraints cross
};

// CDT of prepared.vertices with every constraint segment. Constraints through other vertices are split there;
// crossing constraints get a Steiner vertex at the crossing (exact intersection, rounded to double), its z
// interpolated along the lower-indexed constraint. Fewer than 3 vertices, or all collinear: no triangles.
CdtResult triangulate_cgal(const PreparedInput& prepared);

}  // namespace cdtgpu
