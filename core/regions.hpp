// TIN regions: what GIS users expect of boundaries, holes and concave hulls, applied to a finished CDT.
//
//   PreparedInput p = prepare(in);
//   CdtResult r = triangulate_cgal(p);                 // or gpu::GpuCdt::triangulate: the same mesh
//   RegionRules rules = region_rules(in, parts, p, 250);  // parts: each input's role; max edge 250 m (0:
//   none) RegionStats s = apply_regions(r.mesh, p, rules);   // r.mesh keeps the triangles inside, canonical
//
// Membership is decided exactly by constrained edges, never by point-in-polygon on floats: the mesh edges
// that lie on each constraint are found by walking the mesh from one end to the other (verify.cpp's walk),
// then a flood fill over triangle adjacency counts the region edges crossed from the outside (CGAL's nesting
// levels, as in its polygon-triangulation example). It runs on all CPU cores after either backend, so both
// give the same bytes, whatever the thread count: 2M points + 500K segments with a boundary and a hole take
// about 60 ms on the 16-thread H100 machine (docs/performance.md, "Regions").
#pragma once
#include <cstdint>
#include <vector>

#include "core/input_parts.hpp"
#include "core/model.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

struct RegionRules {
  // Per prepared constraint: 1 when it is an edge of a boundary or hole ring. Empty: no regions.
  std::vector<uint8_t> region_edge;
  // Nesting level of the outside (beyond the hull) is 0; crossing a region edge adds 1. Triangles at odd
  // levels are inside when outside_kept is false (some boundary was given), at even levels when it is true
  // (only holes were given: the hull is the domain and holes cut it).
  bool outside_kept = false;
  // > 0: repeatedly drop triangles reached from the outside across an edge longer than max_edge that is not
  // constrained (constraints of any role stop the trimming). 0: no trimming.
  double max_edge = 0;
};

struct RegionStats {
  uint64_t triangles_outside = 0;  // dropped by boundaries and holes
  uint64_t triangles_trimmed = 0;  // dropped by max_edge (and not already outside)
  uint64_t vertices_removed = 0;   // vertices left in no triangle
};

// The rules for the inputs' roles: region edges from the lines of boundary and hole inputs; the outside is
// kept when no boundary input has lines.
RegionRules region_rules(const InputSet& in, const std::vector<InputPart>& parts,
                         const PreparedInput& prepared, double max_edge);

// Region edge flags for prepared.constraints: a constraint is a region edge when its two ends are the two
// ends of an odd number of segments of `rings` (by exact (x, y)); rings are closed, lines open. Even: the
// segment is crossed twice (an edge shared by adjacent boundaries is inside their union). Collinear partial
// overlaps are resolved the same way on the mesh edges, by apply_regions.
std::vector<uint8_t> region_constraints(const PreparedInput& prepared, const std::vector<Polyline>& rings);

// Region lines that do not close: the prepared vertices that region edges meet an odd number of times (closed
// rings meet each an even number: an edge two rings share drops out at both ends). Their regions leak, the
// nesting levels going around an open end.
struct OpenEnds {
  uint64_t count = 0;
  uint32_t first = 0;  // the first such vertex, when count > 0
};
OpenEnds open_region_ends(const PreparedInput& prepared, const RegionRules& rules);
// "boundary and hole lines do not close (N open ends, the first at (x, y))", for the messages that name them.
std::string open_ends_text(const PreparedInput& prepared, const OpenEnds& open);

// Drops the triangles outside the domain and those trimmed, then the vertices left in no triangle. `mesh` is
// the CDT of `prepared` in canonical order; it stays canonical. A mesh without triangles is left as it is; one
// of 1,431,655,765 triangles or more (half-edges numbered in 32 bits) is a UsageError.
RegionStats apply_regions(Mesh& mesh, const PreparedInput& prepared, const RegionRules& rules);

}  // namespace cdtgpu
