// TIN to DEM grid (rules in raster.hpp). Triangles are bucketed by the rows their bounding box spans (a CSR
// list, each row's triangles in mesh order), then rows are filled in parallel: each row walks its triangles
// in order and claims the centres inside each one that no earlier triangle claimed. Cost: O(triangles + rows
// spanned + centres tested), centres tested being about twice the covered cells (bounding boxes, not
// triangles); memory: the grid plus one index per (triangle, row) pair.
#include "core/raster.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <execution>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/predicates.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

namespace {

// Smallest k with k * cell >= v, largest with k * cell <= v: the division's rounding is corrected with the
// same product the grid uses for its centres.
int64_t ceil_index(double v, double cell) {
  auto k = int64_t(std::ceil(v / cell));
  while (double(k) * cell < v) ++k;
  while (double(k - 1) * cell >= v) --k;
  return k;
}
int64_t floor_index(double v, double cell) {
  auto k = int64_t(std::floor(v / cell));
  while (double(k) * cell > v) --k;
  while (double(k + 1) * cell <= v) ++k;
  return k;
}

}  // namespace

GridSpec grid_for(const Mesh& mesh, double cell, uint64_t max_cells) {
  if (!(cell > 0) || !std::isfinite(cell))
    throw UsageError("the grid cell size must be a positive number, not " + number_text(cell));
  if (mesh.triangles.empty())
    throw UsageError("the mesh has no triangles: there is no surface to rasterise into a grid");
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) {
      const Point3& p = mesh.vertices.at(v);
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    }
  const double limit = 9e15;  // integer cell indices stay exact in double
  if (std::fabs(x0 / cell) > limit || std::fabs(x1 / cell) > limit || std::fabs(y0 / cell) > limit ||
      std::fabs(y1 / cell) > limit)
    throw UsageError("the grid cell size " + number_text(cell) + " is too small for coordinates this large");
  GridSpec g;
  g.cell = cell;
  g.ix0 = floor_index(x0, cell);
  g.iy0 = floor_index(y0, cell);
  g.ncols = uint64_t(ceil_index(x1, cell) - g.ix0 + 1);
  g.nrows = uint64_t(ceil_index(y1, cell) - g.iy0 + 1);
  if (double(g.ncols) * double(g.nrows) > double(max_cells))
    throw UsageError("a grid of cell size " + number_text(cell) + " would have " +
                     std::to_string(g.ncols) + " x " + std::to_string(g.nrows) + " cells (at most " +
                     std::to_string(max_cells) + "): choose a larger --cell");
  return g;
}

double interpolate(const Point3& a, const Point3& b, const Point3& c, double x, double y) {
  // At a vertex the formula gives b.z or c.z only up to rounding (a.z + (b.z - a.z) need not be b.z when the
  // two differ in sign or by more than a factor of two): take the vertex's own z, so a DEM read from a grid
  // comes back unchanged when rasterised at its own cells.
  if (x == a.x && y == a.y) return a.z;
  if (x == b.x && y == b.y) return b.z;
  if (x == c.x && y == c.y) return c.z;
  const double d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  const double s = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / d;
  const double t = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / d;
  return a.z + s * (b.z - a.z) + t * (c.z - a.z);
}

Raster rasterise(const Mesh& mesh, const GridSpec& g) {
  Raster r;
  r.spec = g;
  if (g.ncols == 0 || g.nrows == 0) return r;
  resize_touched(r.z, g.ncols * g.nrows);  // then NODATA on all cores: 800 MB at 10^8 cells
  tbb::parallel_for(tbb::blocked_range<size_t>(0, r.z.size(), 1 << 18), [&](const tbb::blocked_range<size_t>& b) {
    std::fill(r.z.begin() + b.begin(), r.z.begin() + b.end(), Raster::nodata);
  });
  const size_t nt = mesh.triangles.size();

  // The rows (and columns) of centres each triangle's bounding box may hold, clamped to the grid.
  struct Span {
    uint64_t r0 = 1, r1 = 0, c0 = 1, c1 = 0;  // empty unless r0 <= r1 and c0 <= c1
  };
  std::vector<Span> span(nt);
  const auto top = g.iy0 + int64_t(g.nrows) - 1;
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Point3 &a = mesh.vertices.at(tri[0]), &b = mesh.vertices.at(tri[1]), &c = mesh.vertices.at(tri[2]);
    const int64_t ix0 = std::max(ceil_index(std::min({a.x, b.x, c.x}), g.cell), g.ix0);
    const int64_t ix1 =
        std::min(floor_index(std::max({a.x, b.x, c.x}), g.cell), g.ix0 + int64_t(g.ncols) - 1);
    const int64_t iy0 = std::max(ceil_index(std::min({a.y, b.y, c.y}), g.cell), g.iy0);
    const int64_t iy1 = std::min(floor_index(std::max({a.y, b.y, c.y}), g.cell), top);
    if (ix0 > ix1 || iy0 > iy1) continue;
    span[t] = {uint64_t(top - iy1), uint64_t(top - iy0), uint64_t(ix0 - g.ix0), uint64_t(ix1 - g.ix0)};
  }
  std::vector<uint64_t> start(g.nrows + 1, 0);
  for (const Span& s : span)
    for (uint64_t row = s.r0; row <= s.r1 && s.c0 <= s.c1; ++row) ++start[row + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<uint32_t> list(start.back());
  {
    std::vector<uint64_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < nt; ++t)
      for (uint64_t row = span[t].r0; row <= span[t].r1 && span[t].c0 <= span[t].c1; ++row)
        list[fill[row]++] = uint32_t(t);
  }

  std::vector<uint64_t> rows(g.nrows);
  std::iota(rows.begin(), rows.end(), uint64_t(0));
  std::for_each(std::execution::par, rows.begin(), rows.end(), [&](uint64_t row) {
    const double y = g.y(row);
    double* out = r.z.data() + row * g.ncols;
    std::vector<bool> claimed(g.ncols, false);
    for (uint64_t k = start[row]; k < start[row + 1]; ++k) {
      const uint32_t t = list[k];
      const Triangle& tri = mesh.triangles[t];
      const Point3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
      const int o = pred::orient2d({a.x, a.y}, {b.x, b.y}, {c.x, c.y});
      if (o == 0) continue;  // a degenerate triangle covers no area
      for (uint64_t col = span[t].c0; col <= span[t].c1; ++col) {
        if (claimed[col]) continue;
        const pred::XY p{g.x(col), y};
        if (pred::orient2d({a.x, a.y}, {b.x, b.y}, p) * o < 0 ||
            pred::orient2d({b.x, b.y}, {c.x, c.y}, p) * o < 0 ||
            pred::orient2d({c.x, c.y}, {a.x, a.y}, p) * o < 0)
          continue;
        claimed[col] = true;
        out[col] = interpolate(a, b, c, p.x, p.y);
      }
    }
  });
  return r;
}

}  // namespace cdtgpu
