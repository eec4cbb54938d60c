// Inputs that are hard for tiles (tests/tiles_test on CGAL tiles, tests/gpu_tiles_test on the device's final
// test): points and constraints on and across tile borders, co-circular grids, duplicates, clusters, flat rows.
#pragma once
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
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
          {"footprint rings", footprint_rings()}};
}

}  // namespace cdtgpu::tile_layouts
