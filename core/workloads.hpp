// Deterministic synthetic inputs for the benchmark and the tests: uniform points, non-crossing constraints taken
// from the Delaunay triangulation of a random subset, and a DEM grid with its contour lines.
// Every number comes from std::mt19937_64 (its output sequence is fixed by the C++ standard) through the
// hand-written mappings below, never through std:: distributions, whose output differs between libraries.
#pragma once
#include <cstdint>
#include <random>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

// The 53 high bits of one draw as a double in [0, 1): (r >> 11) * 2^-53, exact.
double unit_double(std::mt19937_64& rng);
double unit_double(uint64_t draw);  // the same, of a draw already made

// Uniform integer in [0, bound), bound > 0; rejection of the 2^64 mod bound lowest raw values keeps it unbiased.
uint64_t uniform_below(std::mt19937_64& rng, uint64_t bound);

// The square of the uniform workloads, UTM-like metres: x in [500000, 510000), y in [6000000, 6010000).
constexpr double kUniformX0 = 500000, kUniformY0 = 6000000, kUniformSide = 10000;

// n points; per point three draws u_x, u_y, u_z, in that order:
//   x = (500000000 + floor(u_x * 1e7)) / 1000   (millimetres, so duplicates are possible but rare)
//   y = (6000000000 + floor(u_y * 1e7)) / 1000
//   z = floor(u_z * 1e5) / 1000                 (0 .. 100 m)
// Source name "uniform(n=N,seed=S)".
InputSet uniform_points(uint64_t n, uint64_t seed);

// Appends m constraints (two-point polylines, source "dt-edges(m=M,f=F,seed=S)") to `in`: distinct random edges
// of the Delaunay triangulation of a random subset of in.points holding a fraction f (0 < f <= 1) of them.
// Edges of one triangulation never cross, and they end on input points. The subset's points are deduplicated
// and sorted by (x, y) and its edges sorted by vertex index before sampling, so the choice does not depend
// on CGAL's internal order. A smaller f gives longer constraints: the subset's spacing is 1/sqrt(f) times the
// full set's, so a constraint is about 1.13/sqrt(f) point spacings long and crosses on the order of that many
// triangles of the full triangulation. Throws UsageError when m exceeds the subset triangulation's edges.
void add_dt_edge_constraints(InputSet& in, uint64_t m, double f, uint64_t seed);

// Appends contour-like chains (source-less polylines) to n uniform points: the points of every fourth band of one
// point spacing's height (kUniformSide / sqrt(n)) joined in x order, about n / 4 segments of about one spacing.
// Chains of disjoint bands never cross, and an x-monotone chain through all of a band's points has no vertex
// inside a segment. For sizes where add_dt_edge_constraints is too slow (its CGAL run takes minutes at 256M).
void add_band_chains(InputSet& in);

struct TerrainOptions {
  uint32_t grid = 100;         // DEM nodes per side (grid x grid points)
  double spacing = 10;         // metres between DEM nodes
  uint32_t hills = 12;         // Gaussian hills
  double sigma_min = 0.05;     // hill widths (standard deviations) as fractions of the grid's extent
  double sigma_max = 0.15;
  uint32_t levels = 24;        // contour levels, evenly spread between the terrain's min and max
  uint32_t contour_step = 2;   // contour lattice spacing in DEM cells
  uint64_t seed = 1;
};

// The terrain's height at (x, y) relative to the grid origin (metres): a sum of seeded Gaussian hills.
struct Terrain {
  std::vector<double> cx, cy, sigma, height;  // per hill
  double operator()(double x, double y) const;
};
Terrain make_terrain(const TerrainOptions& options);

// DEM points (source "terrain-dem(grid=G,seed=S)") at (x0 + i*spacing, y0 + j*spacing), z rounded to the mm,
// plus contour polylines (source "terrain-contours(levels=L,seed=S)") extracted with marching squares on a
// lattice of contour_step cells offset by half a cell, so that contour vertices never fall on DEM nodes.
// Contours of different levels never cross, and neither do pieces of one level (saddles are resolved by the
// cell's centre value, the same way for every level). Origin (x0, y0) = (500000, 6000000).
InputSet terrain_workload(const TerrainOptions& options);

// Order-sensitive FNV-1a hash of every coordinate's bits and every polyline's shape: equal inputs, equal hash.
uint64_t checksum(const InputSet& in);

}  // namespace cdtgpu
