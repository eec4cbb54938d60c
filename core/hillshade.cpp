// Hillshade and tint of a DEM grid (see hillshade.hpp). O(cells), one pass per row, rows in parallel.
#include "core/hillshade.hpp"

#include <algorithm>
#include <cmath>
#include <execution>
#include <numbers>
#include <numeric>

namespace cdtgpu {

double preview_cell(const Mesh& mesh, uint32_t pixels) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const Point3& p : mesh.vertices)
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  const double extent = std::max(x1 - x0, y1 - y0);
  return extent > 0 && std::isfinite(extent) ? extent / std::max<uint32_t>(pixels - 1, 1) : 1.0;
}

std::vector<float> hillshade(const Raster& dem) {
  const GridSpec& g = dem.spec;
  std::vector<float> shade(g.ncols * g.nrows, -1.0f);
  const double az = 315 * std::numbers::pi / 180, alt = 45 * std::numbers::pi / 180;
  const double lx = std::sin(az) * std::cos(alt), ly = std::cos(az) * std::cos(alt), lz = std::sin(alt);
  std::vector<uint64_t> rows(g.nrows);
  std::iota(rows.begin(), rows.end(), uint64_t(0));
  std::for_each(std::execution::par, rows.begin(), rows.end(), [&](uint64_t row) {
    for (uint64_t col = 0; col < g.ncols; ++col) {
      const double e = dem.at(row, col);
      if (e == Raster::nodata) continue;
      auto value = [&](int dr, int dc, double& v) {
        const int64_t r = int64_t(row) + dr, c = int64_t(col) + dc;
        if (r < 0 || c < 0 || r >= int64_t(g.nrows) || c >= int64_t(g.ncols)) return false;
        v = dem.at(uint64_t(r), uint64_t(c));
        return v != Raster::nodata;
      };
      // A missing neighbour (edge of the grid or NODATA) is the opposite one mirrored through the centre, so
      // a plane keeps its slope up to the edge; a diagonal one with both missing is extended from the two
      // sides next to it; an axis one with both missing is the centre's own value.
      auto axis = [&](int dr, int dc) {
        double v = e;
        if (value(dr, dc, v)) return v;
        return value(-dr, -dc, v) ? 2 * e - v : e;
      };
      auto z = [&](int dr, int dc) {
        double v = e;
        if (value(dr, dc, v)) return v;
        if (value(-dr, -dc, v)) return 2 * e - v;
        return dr && dc ? axis(dr, 0) + axis(0, dc) - e : e;
      };
      // Row 0 is north: dz/dy (north positive) is the upper row minus the lower one.
      const double dzdx =
          ((z(-1, 1) + 2 * z(0, 1) + z(1, 1)) - (z(-1, -1) + 2 * z(0, -1) + z(1, -1))) / (8 * g.cell);
      const double dzdy =
          ((z(-1, -1) + 2 * z(-1, 0) + z(-1, 1)) - (z(1, -1) + 2 * z(1, 0) + z(1, 1))) / (8 * g.cell);
      const double n = std::sqrt(dzdx * dzdx + dzdy * dzdy + 1);
      shade[row * g.ncols + col] = float(std::max(0.0, (-dzdx * lx - dzdy * ly + lz) / n));
    }
  });
  return shade;
}

std::vector<uint8_t> hillshade_rgba(const Raster& dem) {
  const std::vector<float> shade = hillshade(dem);
  double lo = INFINITY, hi = -INFINITY;
  for (double v : dem.z)
    if (v != Raster::nodata) lo = std::min(lo, v), hi = std::max(hi, v);
  // Low green, middle brown, high near white.
  static constexpr double ramp[3][3] = {{0.32, 0.55, 0.30}, {0.72, 0.60, 0.40}, {0.96, 0.95, 0.93}};
  std::vector<uint8_t> rgba(shade.size() * 4, 0);
  for (size_t i = 0; i < shade.size(); ++i) {
    if (shade[i] < 0) continue;
    const double t = hi > lo ? (dem.z[i] - lo) / (hi - lo) : 0.5;
    const int k = t < 0.5 ? 0 : 1;
    const double f = t < 0.5 ? t * 2 : t * 2 - 1;
    const double light = 0.3 + 0.7 * shade[i];
    for (int ch = 0; ch < 3; ++ch) {
      const double c = (ramp[k][ch] + f * (ramp[k + 1][ch] - ramp[k][ch])) * light;
      rgba[i * 4 + ch] = uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255));
    }
    rgba[i * 4 + 3] = 255;
  }
  return rgba;
}

void draw_edges(std::vector<uint8_t>& rgba, const GridSpec& g, const Points& vertices,
                const std::vector<Edge>& edges) {
  // Pixel (col, row) covers the cell centred at (g.x(col), g.y(row)).
  const double left = double(g.ix0) * g.cell, top = double(g.iy0 + int64_t(g.nrows) - 1) * g.cell;
  auto plot = [&](double x, double y) {
    const double c = std::floor((x - left) / g.cell + 0.5), r = std::floor((top - y) / g.cell + 0.5);
    if (c < 0 || r < 0 || c >= double(g.ncols) || r >= double(g.nrows)) return;
    uint8_t* p = rgba.data() + (uint64_t(r) * g.ncols + uint64_t(c)) * 4;
    p[0] = 25, p[1] = 35, p[2] = 90, p[3] = 255;
  };
  const double right = double(g.ix0 + int64_t(g.ncols) - 1) * g.cell, bottom = double(g.iy0) * g.cell;
  for (const Edge& e : edges) {
    const Point3 &a = vertices.at(e[0]), &b = vertices.at(e[1]);
    // The part of a + t (b - a) inside the picture (one cell of margin): t0 .. t1.
    double t0 = 0, t1 = 1;
    auto clip = [&](double p, double d, double lo, double hi) {
      if (d == 0) {
        if (p < lo || p > hi) t1 = -1;
        return;
      }
      double u = (lo - p) / d, w = (hi - p) / d;
      if (u > w) std::swap(u, w);
      t0 = std::max(t0, u), t1 = std::min(t1, w);
    };
    clip(a.x, b.x - a.x, left - g.cell, right + g.cell);
    clip(a.y, b.y - a.y, bottom - g.cell, top + g.cell);
    if (t0 > t1) continue;
    // At most half a pixel per step.
    const double len = (t1 - t0) * std::max(std::fabs(b.x - a.x), std::fabs(b.y - a.y)) / g.cell;
    const double steps = std::ceil(len * 2);
    for (double i = 0; i <= steps; ++i) {
      const double t = steps > 0 ? t0 + (t1 - t0) * (i / steps) : t0;
      plot(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y));
    }
  }
}

}  // namespace cdtgpu
