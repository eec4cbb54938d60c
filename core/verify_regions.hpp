// verify for meshes made with boundary and hole inputs: the CDT restricted to the domain.
//
//   RegionRules rules = region_rules(in, parts, prepared, 0);
//   VerifyReport r = verify_regions(mesh, prepared, rules);
//
// Independent of apply_regions' flood fill: the CDT of `prepared` is computed with the CGAL backend and
// checked by verify_mesh; each of its triangles is in the domain when a point strictly inside it (checked
// with exact orientation; for a sliver with no such point in doubles, its exact centroid) is inside by the
// parity of region segments crossed by a ray to +x (exact orientation tests, half-open in y), odd or even as
// RegionRules says, and not trimmed: with rules.max_edge, the triangles reached from beyond the hull across
// edges longer than it that lie on no constraint (the constrained edges as verify_mesh finds them) are left
// out. The mesh must hold exactly the rest, with the CDT's vertices and z. Region lines that do not close
// (an end met an odd number of times) are a UsageError: their regions leak, which the parity does not model. The parity is that of the input's
// segments: where a crossing's rounded Steiner vertex moves a region edge off its segment, a sliver between
// the two may be judged otherwise than the mesh's region edges judge it (docs/testing.md).
#pragma once
#include "core/regions.hpp"
#include "core/verify.hpp"

namespace cdtgpu {

VerifyReport verify_regions(const Mesh& mesh, const PreparedInput& prepared, const RegionRules& rules,
                            size_t max_failures = 20);

}  // namespace cdtgpu
