// One `cdtgpu triangulate` run as data: its options, and what each stage (cli/stages.hpp) made of it. The single
// run and `cdtgpu batch` (cli/batch.hpp) fill it by the same stage functions, in the same order.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/cdt_cgal.hpp"
#include "core/contours.hpp"
#include "core/input_parts.hpp"
#include "core/prepare.hpp"
#include "core/projection.hpp"
#include "core/resolve.hpp"
#include "core/raster.hpp"
#include "core/tile_workers.hpp"
#include "core/tiles.hpp"
#include "core/stats.hpp"
#include "gpu/contours.hpp"
#include "gpu/raster.hpp"
#include "io/mesh_file_ahead.hpp"
#include "io/readers.hpp"
#include "io/tiles_dir.hpp"
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
  std::string initial_dt = "insertion";  // the GPU Delaunay build's start: insertion or voronoi (gpu/delaunay.hpp)
  std::string stats_path;    // empty: none
  std::string grid_out;      // ESRI ASCII grid of the TIN (core/raster.hpp); empty: none
  double cell = 1.0;         // its cell size
  std::string contours_out;  // contour lines as WKT (core/contours.hpp); empty: none
  double interval = 10.0;    // their interval
  std::string preview;       // hillshaded PNG of the TIN (core/hillshade.hpp); empty: none
  double max_edge = 0;       // > 0: concave-hull trimming (core/regions.hpp)
  int64_t max_tile_points = -1;  // tiles of at most this many points (core/tiles.hpp); 0: never; -1: auto
  std::string tiles_out;         // the mesh as one file per tile plus index.geojson (io/tiles_dir.hpp); empty: none
  std::string devices;           // GPUs for tiled runs (gpu/devices.hpp); empty: all hardware GPUs when tiled
  const RankTiles* ranks = nullptr;  // MPI ranks: rank 0 hands tiles to the others (cli/mpi.hpp); null: one process
  // Another process of the run may take the same GPUs (MPI ranks beyond one a GPU, or GPUs picked by hand under
  // MPI): no device memory made ahead (gpu/device_memory_pool.hpp), which would leave the other little.
  bool devices_shared = false;
  // An MPI rank's GPU when neither --device nor --devices says: the host's (rank_gpu mod n)-th, chosen by the
  // device's start (gpu::ContextOptions::nth_gpu), shared when host_ranks exceed the host's GPUs. -1: not a
  // rank.
  int rank_gpu = -1;
  int host_ranks = 1;
  const TilesDirSharing* tiles_sharing = nullptr;  // --tiles-out's files written by every rank; null: here
};

class GpuStart;

struct Job {
  TriangulateOptions options;
  bool stage_progress = true;  // a progress line per long stage on a terminal (a batch draws its own)
  std::string stats_copy;      // a second --stats file (batch --stats-dir); empty: none
  bool keep_device_buffers = false;  // a batch: the device's buffers stay for the next job (gpu::GpuCdt)

  // check_job
  WriteOptions write;                   // with the format decided
  std::vector<std::string> input_paths;  // the inputs without their :key=value options
  std::vector<std::string> outputs;      // every file the run writes (checked against the inputs)
  RunStats stats;
  std::optional<uint64_t> estimated_points;  // from the files' sizes and headers, made once (stages.cpp)

  // read_job, prepare_job
  InputSet in;
  std::vector<InputPart> parts;  // what each input added, with its role and z rule
  Crs crs;
  PreparedInput prepared;
  // begin_mesh_file: the output's vertex section being written from prepared.vertices' storage, which stays
  // until mesh_ahead->wait() (stages.cpp: vertices_may_go) or goes to mesh_ahead->free_after_writing
  // (drop_prepared). Declared after `prepared`: gone before it.
  std::unique_ptr<MeshFileAhead> mesh_ahead;

  // choose_backend
  bool want_gpu = false;
  std::string backend_reason;
  GpuStart* start = nullptr;  // the GPU's start, once asked for
  bool tiles_ahead = false;   // open_tiles_early began the tiles' devices and staging on it

  // resolve_early (a batch's GPU jobs): the constraints resolved in the reader's stage, for triangulate_job
  std::optional<ResolvedInput> resolved_early;
  double resolved_early_ms = 0;

  // triangulate_job (gpu: the device ran it; the raster and contour passes then run there too)
  CdtResult result;
  bool gpu = false;
  std::optional<gpu::GpuRasteriser> gpu_raster;
  std::optional<gpu::GpuContourer> gpu_contours;

  // derive_outputs
  std::optional<Raster> grid, preview;
  std::vector<Contour> contours;
};

}  // namespace cdtgpu
