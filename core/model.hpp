// The data model shared by readers, backends, writers and verify.
#pragma once
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/uninit.hpp"

namespace cdtgpu {

struct Point3 {
  double x = 0, y = 0, z = 0;
  friend bool operator==(const Point3&, const Point3&) = default;
};

// Vertices (as read, prepared, resolved, a mesh's): resize() leaves the new ones for their writer.
using Points = RawVector<Point3>;

// The x and y range of some points; empty until one is added.
struct Bounds {
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  bool empty() const { return !(min_x <= max_x); }
  void add(const Point3& p) {
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
    min_y = std::min(min_y, p.y);
    max_y = std::max(max_y, p.y);
  }
  void add(const Bounds& o) {
    min_x = std::min(min_x, o.min_x), max_x = std::max(max_x, o.max_x);
    min_y = std::min(min_y, o.min_y), max_y = std::max(max_y, o.max_y);
  }
};

// A constraint polyline as read: a contour (open) or a ring such as a building footprint (closed; the
// closing edge from the last point back to the first is implied, the first point is not repeated).
struct Polyline {
  Points points;
  bool closed = false;
  uint32_t source = 0;  // index into InputSet::sources
  uint64_t record = 0;  // 1-based record (shapefile) or line (text) in that source, for messages
};

// What readers repaired instead of dropping; every count is reported in the stats.
struct Repairs {
  uint64_t repeated_vertices = 0;    // consecutive equal vertices in a polyline or ring (zero-length segments)
  uint64_t rings_closed = 0;         // rings whose last vertex did not repeat the first
  uint64_t degenerate_lines = 0;     // polylines left with one distinct vertex: kept as a point
  uint64_t null_shapes = 0;          // shapefile NULL shapes (carry no geometry)
  uint64_t nodata_cells = 0;         // grid cells equal to NODATA_value
};

// Points of LAS inputs (io/read_las) per ASPRS class, kept and skipped by the class=, returns= and withheld
// filters; and the skipped ones by the first filter that skipped them.
struct PointClassCounts {
  struct Count {
    uint64_t kept = 0, skipped = 0;
  };
  std::map<int, Count> by_class;
  uint64_t withheld = 0, other_returns = 0, other_classes = 0;
  bool any = false;  // some LAS input was read

  void add(const PointClassCounts& o) {
    any = any || o.any;
    withheld += o.withheld;
    other_returns += o.other_returns;
    other_classes += o.other_classes;
    for (const auto& [cls, c] : o.by_class) {
      by_class[cls].kept += c.kept;
      by_class[cls].skipped += c.skipped;
    }
  }
};

struct InputSet {
  std::vector<std::string> sources;  // file names in the order they were read
  Points points;                     // loose vertices: DEM points, grid cells, point features
  std::vector<Polyline> lines;       // constraints
  Repairs repairs;
  PointClassCounts point_classes;
  std::string source_crs_wkt;        // WKT1 of the first .prj seen, if any
  // Set by io/input_spec's read_inputs: readers give vertices without z (2D geometry, no z field) the z
  // missing_z() instead of 0, and core/drape's apply_z_rules resolves every one before prepare. Off: z = 0.
  bool nan_for_missing_z = false;
  // Ranges of `points` whose x and y bounds their reader found as it wrote them (LAS): choose_crs reads those
  // points no more (0.21 s at 1B points on 32 threads). Appending keeps them true; whatever moves or drops points
  // of such a range must clear them (choose_crs checks that they lie inside `points` and do not overlap).
  struct Extent {
    size_t begin = 0, end = 0;
    Bounds bounds;
  };
  std::vector<Extent> point_extents;
};

// A NaN with its own payload: "this vertex was read without z". Any other NaN is still bad input.
inline double missing_z() { return std::bit_cast<double>(uint64_t(0x7ff8'0000'007a'0000)); }
inline bool is_missing_z(double z) { return std::bit_cast<uint64_t>(z) == 0x7ff8'0000'007a'0000; }

using Triangle = std::array<uint32_t, 3>;  // vertex indices, counter-clockwise
using Edge = std::array<uint32_t, 2>;
// Triangles as made (downloads, merges, the tiles' canonical order): resize() leaves the new ones for their
// writer, on all cores; std::vector's would first zero them on one core (1 s for 512M triangles).
using Triangles = RawVector<Triangle>;

// A TIN. Canonical order (canonical.hpp): vertices sorted by (x, y); each triangle starts at its smallest
// index and stays counter-clockwise; triangles sorted lexicographically.
struct Mesh {
  Points vertices;
  Triangles triangles;
};

}  // namespace cdtgpu
