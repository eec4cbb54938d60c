// Checks that a mesh is the constrained Delaunay triangulation of its inputs, with exact predicates.
#pragma once
#include <string>
#include <vector>

#include "core/model.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

struct VerifyReport {
  std::vector<std::string> failures;  // each a readable sentence naming vertices / triangles by index
  uint64_t constrained_edges = 0;
  uint64_t steiner_vertices = 0;      // mesh vertices that are not input vertices
  bool ok() const { return failures.empty(); }
};

// Valid triangulation of the convex hull (edge-manifold, all triangles CCW, boundary = convex hull,
// V - E + F = 1), every input vertex present, every constraint a union of mesh edges as the rules split it
// (docs/rules.md: the pieces and Steiner vertices of resolve_constraints, each piece an edge, no other vertex), every non-constrained edge locally Delaunay under CGAL's perturbed
// incircle. Stops collecting after max_failures. `constrained`, if given, receives the mesh edges that lie on
// constraints, each (smaller vertex, larger vertex), sorted.
VerifyReport verify_mesh(const Mesh& mesh, const PreparedInput& prepared, size_t max_failures = 20,
                         std::vector<Edge>* constrained = nullptr);

}  // namespace cdtgpu
