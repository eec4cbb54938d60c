// Contour lines of a TIN by marching triangles, chained into polylines.
// Usage:
//   std::vector<Contour> lines = contour_lines(mesh, 10.0);   // levels at every multiple of 10
//   write_contours_wkt_file(lines, crs, "contours.wkt");        // io/gis_writers.hpp: LINESTRING Z per line
//
// Rules, so the lines are one deterministic function of the mesh:
// - Levels are k * interval (one product in double) for every integer k with the level inside [zmin, zmax].
// - A vertex with z >= level is above, z < level below: a vertex exactly at the level counts as above. A
//   triangle with both kinds gives one segment between the two edges that join an above and a below vertex.
// - The point on such an edge u (below) - v (above): v itself when v.z == level, else u + t * (v - u) with
//   t = (level - u.z) / (v.z - u.z), computed from (u, v) in that order, so both triangles of the edge get
//   the same double. Its z is the level.
// - Segments are oriented with higher ground on the left (counter-clockwise around hills) and joined through
//   shared edges: a line that reaches the mesh boundary is open, one that comes back is closed (its last
//   point repeats its first). Consecutive equal points (where a vertex lies on the level) are written once; a
//   line left with fewer than two distinct points is dropped.
// - Order: by level, then open lines before closed ones, each by the mesh index of the triangle of its first
//   segment (a closed line starts in the first triangle it crosses).
#pragma once
#include <cstdint>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

struct Contour {
  double level = 0;
  bool closed = false;
  Points points;  // closed: the last point equals the first
};

// Throws UsageError for an interval that is not a positive finite number or more than max_levels levels.
std::vector<Contour> contour_lines(const Mesh& mesh, double interval, uint64_t max_levels = 100000);

// The pieces contour_lines is made of, for other producers of segments (gpu/contours: marching triangles on
// the GPU, chaining here) that must give the same lines.

// The levels inside the mesh's z range: level i is double(k0 + i) * interval. Same errors as contour_lines.
struct ContourLevels {
  int64_t k0 = 0;
  size_t count = 0;
  double interval = 1;
  double level(size_t i) const { return double(k0 + int64_t(i)) * interval; }
};
ContourLevels contour_levels(const Mesh& mesh, double interval, uint64_t max_levels = 100000);

// A segment of one triangle at one level: from the edge it enters through to the edge it leaves through
// (keys of contour_edge_key), higher ground on the left.
struct ContourSegment {
  uint64_t from, to;
  Point3 p, q;
};
uint64_t contour_edge_key(uint32_t a, uint32_t b);
// The lines of one level from its segments in mesh order of their triangles (contour_lines' chaining rules).
std::vector<Contour> chain_contours(double level, const std::vector<ContourSegment>& segs);

}  // namespace cdtgpu
