// Inputs that are hard for tiles (tests/tiles_test on CGAL tiles, tests/gpu_tiles_test on the device's final
// test): points and constraints on and across tile borders, co-circular grids, duplicates, clusters, flat rows.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "core/repair.hpp"
#include "core/workloads.hpp"

namespace cdtgpu::tile_layouts {

inline Polyline line(Points pts, bool closed = false) {
  Polyline l;
  l.points = std::move(pts);
  l.closed = closed;
  return l;
}

inline InputSet random_points(size_t n, uint64_t seed, double side = 1000) {
  std::mt19937_64 rng(seed);
  InputSet in;
  for (size_t i = 0; i < n; ++i) in.points.push_back({unit_double(rng) * side, unit_double(rng) * side, double(i)});
  return in;
}

inline InputSet crossing_constraints() {
  InputSet in = random_points(1500, 2);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 60; ++i)
    in.lines.push_back(line({{unit_double(rng) * 1000, unit_double(rng) * 1000, 1},
                             {unit_double(rng) * 1000, unit_double(rng) * 1000, 2}}));
  return in;
}

inline InputSet constraints_across_every_tile() {
  InputSet in = random_points(2000, 3);
  in.lines.push_back(line({{-1, -1, 0}, {1001, 1001, 0}}));
  in.lines.push_back(line({{-1, 1001, 0}, {1001, -1, 0}}));  // and crosses the first
  in.lines.push_back(line({{-5, 500, 0}, {1005, 500.25, 0}}));
  return in;
}

inline InputSet long_nearly_parallel_constraints() {
  InputSet in = random_points(2000, 4);
  for (int i = 0; i < 10; ++i)  // thin triangles with huge circumcircles
    in.lines.push_back(line({{0, 100.0 * i + 3, 0}, {1000, 100.0 * i + 3.5, 0}}));
  return in;
}

inline InputSet dem_grid() {
  InputSet in;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) in.points.push_back({double(i), double(j), double((i * 7 + j * 3) % 11)});
  return in;
}

inline InputSet duplicates_on_both_sides() {
  InputSet in;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      in.points.push_back({double(i), double(j) * 0.5, 1});
      in.points.push_back({double(i), double(j) * 0.5, 2});  // a duplicate, merged by prepare
    }
  in.lines.push_back(line({{0, 0, 0}, {29, 14.5, 0}}));
  return in;
}

inline InputSet clustered_points() {
  std::mt19937_64 rng(9);
  InputSet in;
  for (int c = 0; c < 5; ++c) {
    const double cx = unit_double(rng) * 1e5, cy = unit_double(rng) * 1e5;
    for (int i = 0; i < 400; ++i) in.points.push_back({cx + unit_double(rng), cy + unit_double(rng), 0});
  }
  return in;
}

inline InputSet collinear_rows() {
  InputSet in;
  for (int i = 0; i < 300; ++i) in.points.push_back({double(i), 0, 0});  // one row: flat triangles beside it
  for (int i = 0; i < 300; ++i) in.points.push_back({double(i) + 0.5, 1e-9 * (i % 3), 0});
  for (int i = 0; i < 50; ++i) in.points.push_back({double(i * 6), 50, 0});
  return in;
}

inline InputSet all_collinear() {
  InputSet in;
  for (int i = 0; i < 100; ++i) in.points.push_back({double(i), 2.0 * i, 0});
  return in;
}

inline InputSet footprint_rings() {
  InputSet in = random_points(1500, 11);
  for (int k = 0; k < 12; ++k) {
    const double x = 80.0 * k + 10, y = 70.0 * k + 20;
    in.lines.push_back(line({{x, y, 0}, {x + 120, y, 0}, {x + 120, y + 90, 0}, {x, y + 90, 0}}, true));
  }
  return in;
}

inline InputSet terrain_with_contours() {
  TerrainOptions o;
  o.grid = 48;
  o.levels = 8;
  return terrain_workload(o);
}

// Lattice soups: points on (and between) the nodes of an m x m lattice with duplicates, collinear rows or
// co-circular rings, and lines along lattice rows, columns and diagonals, between random nodes (crossings at
// rounded points beside T-junctions), contour-like paths that double back on themselves and footprint rings
// sharing walls. CGAL's own crossing handling (tests/cgal_plus.hpp) crashed or looped on 21 of the first 60
// and split 6 otherwise; every path of cdtgpu must give the one mesh of the rules (docs/rules.md).
// `scale` multiplies the points and lines (and widens the lattice): bench/tools/paths_stress runs larger ones.
inline InputSet lattice_soup(uint64_t seed, int scale = 1) {
  std::mt19937_64 rng(seed);
  auto below = [&](uint64_t n) { return int(uniform_below(rng, n)); };
  auto between = [&](int a, int b) { return a + below(uint64_t(b - a + 1)); };
  InputSet in;
  const int m = between(8, 40) * (scale > 1 ? scale / 2 + 1 : 1);
  const double s = std::vector<double>{1.0, 0.1, 3.0, 1e-3, 0.5}[below(5)];
  const double ox = below(2) ? 500000.0 : 0.0, oy = below(2) ? 6000000.0 : 0.0;
  auto at = [&](double i, double j, double z) { return Point3{ox + i * s, oy + j * s, z}; };
  const int kind = below(4), n = between(50, 1200) * scale;
  for (int k = 0; k < n; ++k) {
    if (kind == 0 || below(4) == 0) {
      in.points.push_back(at(between(0, m), between(0, m), below(10)));
    } else if (kind == 1) {
      in.points.push_back(at(unit_double(rng) * m, unit_double(rng) * m, below(10)));
    } else if (kind == 2) {
      in.points.push_back(at(between(0, 4 * m) / 4.0, between(0, m) + (below(20) == 0 ? 1e-9 : 0.0), below(10)));
    } else {
      const double a = below(360) * 3.14159265358979 / 180, r = between(1, 4) * m / 10.0;
      in.points.push_back(at(m / 2.0 + r * std::cos(a), m / 2.0 + r * std::sin(a), below(10)));
    }
  }
  for (int l = 0, lines = below(41) * scale; l < lines; ++l) {
    Polyline p;
    switch (below(6)) {
      case 0: {
        const int r = between(0, m);
        p.points = {at(between(0, m), r, 1), at(between(0, m), r, 1)};
        break;
      }
      case 1: {
        const int c = between(0, m);
        p.points = {at(c, between(0, m), 2), at(c, between(0, m), 2)};
        break;
      }
      case 2: {
        const int a = between(0, m / 2), b = between(0, m / 2), d = between(1, m / 2);
        p.points = {at(a, b, 3), at(a + d, b + d, 3)};
        break;
      }
      case 3:
        p.points = {at(between(0, m), between(0, m), 4), at(between(0, m), between(0, m), 4)};
        break;
      case 4: {
        int x = between(0, m), y = between(0, m);
        for (int k = 0, steps = between(2, 12); k < steps; ++k) {
          p.points.push_back(at(x, y, 5));
          x = std::clamp(x + between(-3, 3), 0, m), y = std::clamp(y + between(-3, 3), 0, m);
        }
        break;
      }
      default: {
        const int x = between(0, m - 3), y = between(0, m - 3), w = between(1, 3), h = between(1, 3);
        p.points = {at(x, y, 6), at(x + w, y, 6), at(x + w, y + h, 6), at(x, y + h, 6)};
        p.closed = true;
      }
    }
    add_polyline(in, std::move(p));  // as a reader hands it over: repeated vertices removed
  }
  return in;
}

// Two constraints within rounding of one line (a decimal diagonal at y ~ 6e6, x ~ 0), overlapping, crossed by a
// third near their overlap: the resolve's rounded crossings cascaded there until they were snapped to piece ends.
inline InputSet nearly_coincident_crossed() {
  InputSet in = random_points(600, 17, 0.2);
  for (Point3& p : in.points) p.y += 6000000;
  const double y0 = 6000000;
  in.lines.push_back(line({{0.056000000000000001, y0 + 0.0029999996, 0}, {0.13200000000000001, y0 + 0.1689999998, 1}}));
  in.lines.push_back(line({{0.073999999999999996, y0 + 0.0710000005, 2}, {0.14999999999999999, y0 + 0.1469999999, 3}}));
  in.lines.push_back(line({{0.026000000000000002, y0 + 0.023, 4}, {0.10100000000000001, y0 + 0.0980000002, 5}}));
  return in;
}

// Every layout above by name.
inline std::vector<std::pair<std::string, InputSet>> all() {
  return {{"crossing constraints", crossing_constraints()},
          {"constraints across every tile", constraints_across_every_tile()},
          {"long nearly parallel constraints", long_nearly_parallel_constraints()},
          {"DEM grid", dem_grid()},
          {"terrain grid with contours", terrain_with_contours()},
          {"duplicates on both sides of borders", duplicates_on_both_sides()},
          {"clustered points", clustered_points()},
          {"collinear rows", collinear_rows()},
          {"all collinear", all_collinear()},
          {"footprint rings", footprint_rings()},
          {"lattice soup", lattice_soup(1)},
          {"nearly coincident constraints crossed by a third", nearly_coincident_crossed()}};
}

}  // namespace cdtgpu::tile_layouts
