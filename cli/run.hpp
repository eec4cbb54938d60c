// The commands behind the CLI: read -> project -> prepare -> triangulate -> write, and verify.
#pragma once
#include <string>
#include <vector>

#include "core/projection.hpp"
#include "io/readers.hpp"
#include "io/writers.hpp"

namespace cdtgpu {

struct InputOptions {
  std::vector<std::string> inputs;
  ReadOptions read;
  CrsRequest crs;
};

struct TriangulateOptions {
  InputOptions input;
  std::string output;        // "-" for stdout; empty: --tiles-out only
  std::string format;        // empty: from the output's extension
  WriteOptions write;
  std::string backend = "auto";  // auto (default: cli/gpu_start.hpp), gpu or cgal (the CPU reference)
  std::string device;           // Vulkan device override for the gpu backend
  std::string stats_path;    // empty: none
  std::string grid_out;      // ESRI ASCII grid of the TIN (core/raster.hpp); empty: none
  double cell = 1.0;         // its cell size
  std::string contours_out;  // contour lines as WKT (core/contours.hpp); empty: none
  double interval = 10.0;    // their interval
  std::string preview;       // hillshaded PNG of the TIN (core/hillshade.hpp); empty: none
  double max_edge = 0;       // > 0: concave-hull trimming (core/regions.hpp)
  int64_t max_tile_points = -1;  // tiles of at most this many points (core/tiles.hpp); 0: never; -1: auto
  std::string tiles_out;         // the mesh as one file per tile plus index.geojson (io/tiles_dir.hpp); empty: none
};

// Returns the process exit code; throws InputError / UsageError for bad input.
int run_triangulate(const TriangulateOptions& options);
int run_verify(const std::string& mesh_path, const InputOptions& options, double max_edge = 0);

}  // namespace cdtgpu
