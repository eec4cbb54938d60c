// cdtgpu bench --table tiles: the tiled CDT (core/tiles) against the single run, in process, on generated
// workloads (uniform points and a quarter as many Delaunay-edge constraints; above 20M points contour-like
// chains through every fourth band of points instead, as many segments; no file I/O).
//
//   BenchOptions o;            // bench/bench.hpp
//   o.table = "tiles";
//   o.sizes = {"2M", "16M"};   // points; a quarter as many constraint segments
//   int code = run_tiles(o);   // prints the table; 1 when a tiled mesh differs from the single run's
//
// Per row, each timed --runs times after a warm-up (median): the single run on the CPU (triangulate_cgal, one
// core; --cgal-runs, skipped above --cgal-max) and on the GPU (gpu::GpuCdt), then the tiled runs: CPU tiles
// on every core (auto tile size, or --tile-points) and GPU tiles streamed through the device (--tile-points,
// or a quarter of the input); with --devices, GPU tiles spread over 2, 4, ... devices too (backend gpu-K, two
// tiles in flight a device). Every mesh is compared with the first single run's, byte for byte. Columns:
// tiles and levels, the share of triangles final in their tiles, the last merge's size and time, resolve and
// total wall time, and the process's peak resident memory after the row.
#pragma once
#include "bench/bench.hpp"

namespace cdtgpu {

int run_tiles(const BenchOptions& options);

}  // namespace cdtgpu
