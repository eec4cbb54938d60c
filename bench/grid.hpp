// cdtgpu bench --table grid: the derived outputs of a TIN, CPU against GPU, on the terrain workload.
//
//   BenchOptions o;          // bench/bench.hpp
//   o.table = "grid";
//   o.sizes = {"1M"};        // DEM points (a square grid of them, 10 m apart, plus its contour lines)
//   o.grid_cells = 10000;    // cells on the grid's long side: 10000 x 10000 = 10^8 cells
//   int code = run_grid(o);  // prints the table; 1 when the GPU's grid or contours differ from the CPU's
//
// Per row: the terrain workload (core/workloads.hpp: a DEM grid and its contour lines as constraints) is
// triangulated once (CGAL backend); then, --runs times each (median reported): core's rasterise over the
// grid, the GPU rasteriser (gpu/raster.hpp; the TIN's upload timed apart), core's contour_lines and the GPU
// contours (gpu/contours.hpp) at 100 levels over the z range. The GPU's grid must equal the CPU's bit for bit
// and its contours the CPU's WKT text. The CPU's grid is then written as ESRI ASCII and as GeoTIFF
// (io/geotiff.hpp; whole files, synced and renamed) and the GeoTIFF read back as vertices, --runs times
// each. Then `cdtgpu triangulate` runs as a child process on the workload
// written as text (.xyz + .wkt), with --grid-out (ESRI ASCII, about 1.1 GB at 10^8 cells) and --contours-out,
// once per backend (cgal, gpu) after one warm-up: the whole-process wall clock, and the written grids and
// contour files must be the same bytes.
#pragma once
#include "bench/bench.hpp"

namespace cdtgpu {

int run_grid(const BenchOptions& options);

}  // namespace cdtgpu
