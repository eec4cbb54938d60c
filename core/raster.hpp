// A TIN rasterised to a DEM grid by linear interpolation inside its triangles (CPU; parallel over rows).
// Usage:
//   Raster dem = rasterise(mesh, 1.0);               // cell centres at multiples of 1 m
//   double z = dem.at(row, col);                      // Raster::nodata outside the triangulated area
//   write_ascii_grid_file(dem, crs, "dem.asc");       // io/gis_writers.hpp
//
// Rules, so the grid is one deterministic function of the mesh:
// - Cell centres lie at integer multiples of the cell size: column c is x = (ix0 + c) * cell, row r (0 = the
//   northmost) is y = (iy0 + nrows - 1 - r) * cell, each one product in double. The grid covers the mesh's
//   bounding box, snapped outward to the next multiples.
// - A centre belongs to the first triangle, in the mesh's order, that contains it (its closed triangle,
// decided
//   by exact orient2d): a centre on an edge or a vertex shared by several triangles takes the one with the
//   smallest index. Centres in no triangle get Raster::nodata.
// - Its value is interpolate(a, b, c, x, y) over that triangle's vertices in the stored order: the one
// formula
//   below, evaluated left to right in double without fused multiply-add (the build sets -ffp-contract=off);
//   a centre exactly at a vertex takes that vertex's z, so a grid DEM comes back unchanged at its own cells.
#pragma once
#include <cstdint>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

struct GridSpec {
  double cell = 1;
  int64_t ix0 = 0, iy0 = 0;  // the southwest cell centre is (ix0 * cell, iy0 * cell)
  uint64_t ncols = 0, nrows = 0;
  double x(uint64_t col) const { return double(ix0 + int64_t(col)) * cell; }
  double y(uint64_t row) const { return double(iy0 + int64_t(nrows - 1 - row)) * cell; }
};

struct Raster {
  static constexpr double nodata = -9999;
  GridSpec spec;
  std::vector<double> z;  // nrows * ncols, row 0 first (north), each row west to east
  double at(uint64_t row, uint64_t col) const { return z[row * spec.ncols + col]; }
};

// The grid that covers the mesh's vertices with centres at multiples of cell. Throws UsageError for a cell
// that is not a positive finite number, a grid of more than max_cells cells (2^28 doubles: 2 GiB), or a mesh
// without triangles.
GridSpec grid_for(const Mesh& mesh, double cell, uint64_t max_cells = uint64_t(1) << 28);

// The value at (x, y) of the plane through a, b, c: the vertex's own z when (x, y) is one of a, b, c, else
//   d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
//   s = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / d
//   t = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / d
//   z = a.z + s * (b.z - a.z) + t * (c.z - a.z)
double interpolate(const Point3& a, const Point3& b, const Point3& c, double x, double y);

Raster rasterise(const Mesh& mesh, const GridSpec& spec);
inline Raster rasterise(const Mesh& mesh, double cell) { return rasterise(mesh, grid_for(mesh, cell)); }

}  // namespace cdtgpu
