// The host half of the Voronoi first stage: the digital dual's triangles, which nothing guarantees, checked
// exactly (core/predicates) and turned into the slots of a valid triangulation of the sphere (gpu/triangulation.hpp)
// over the sites they use, or the sites to demote when they fail.
//
//   std::vector<uint32_t> offenders;
//   std::optional<StartSlots> s = dual_to_slots(xy, dual_triangles, offenders);
//   if (!s) for (uint32_t v : offenders) demote(v);   // then flood again (gpu/voronoi_start.cpp)
//
// Valid means: every triangle strictly counter-clockwise; each directed edge once; the boundary edges one
// simple cycle; every vertex's fan one chain or cycle winding once (a boundary vertex's spanning its interior
// angle); the boundary convex (collinear vertices allowed where they lie between their neighbours) and winding
// once; Euler's V - E + F = 1. A triangulated disc whose map is locally one-to-one and whose boundary is a simple
// convex curve covers the convex region once, so these local checks make it a triangulation of the convex hull
// of its vertices. Pockets between the dual's boundary and the hull (the dual rarely has a convex boundary) are
// closed first by a Graham scan along the boundary, whose triangles are checked with the rest. Cost: O(F) for F
// triangles (bucket sorts by vertex), in parallel passes on all cores; the boundary's walk, pocket filling and
// convexity (O(sqrt F) for a grid's dual) on one.
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "core/big_array.hpp"
#include "core/model.hpp"

namespace cdtgpu::gpu {

struct StartSlots {
  RawVector<uint32_t> verts, nbrs;  // 3 per slot: finite triangles first, then one infinite slot per hull edge
  uint32_t finite = 0;              // finite slots
  uint32_t vertices = 0;            // points used (the slots hold 2 * vertices - 2)
  RawVector<uint32_t> slot_of;      // per point: the last finite slot it is a corner of, or UINT32_MAX
};

// `xy`: 2 doubles per point; `tris`: counter-clockwise (by the grid, not yet by the points) triples of point
// ids, in any order, duplicates allowed. On failure returns nothing and lists in `offenders` the vertices
// whose removal should help (empty: no repair known).
// `oriented`: every triangle is known counter-clockwise (shaders/vd_dual.comp's exact filter decided them all),
// so only their corners' distinctness is checked.
std::optional<StartSlots> dual_to_slots(std::span<const double> xy, RawVector<Triangle> tris,
                                        std::vector<uint32_t>& offenders, bool oriented = false);

}  // namespace cdtgpu::gpu
