// cdtgpu bench: times the CDT of the deterministic workloads (core/workloads.hpp) with a CGAL configured for
// speed and with the GPU backend (gpu/cdt_pipeline.hpp), checks both give the same triangles, and prints a
// table like the paper's (Chen et al. 2026); --ablation prints its Table 3; --table e2e (bench/e2e.hpp) times the
// whole `cdtgpu triangulate` as a child process; --table grid (bench/grid.hpp) the DEM grid and contours.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/model.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

// One run of a backend on a prepared input. The mesh may be in any order (the bench canonicalizes it to
// compare backends); total_ms is the figure the table compares (host wall clock), stage_ms its parts in order.
struct BackendRun {
  Mesh mesh;
  std::vector<std::pair<std::string, double>> stage_ms;
  double total_ms = 0;
  double device_ms = 0;         // GPU: the sum of the device timestamps of its stages
  uint32_t rounds = 0;          // GPU: Delaunay insertion rounds + constraint flip rounds + legalise rounds
  uint64_t peak_device_bytes = 0;
  uint32_t host_fallback = 0;   // GPU: constraints the host safety net inserted (gpu::ConstraintStats)
  std::vector<std::pair<std::string, double>> wall_ms;  // GPU: host clock per pipeline stage (resolve, delaunay, ...)
};
using BenchBackend = std::function<BackendRun(const PreparedInput&)>;

struct BenchOptions {
  std::string table = "all";        // 1, 2, long, terrain, all (those four), dt (Delaunay only), e2e, grid, peer, tiles or las
  bool quick = false;               // 20K..80K points instead of 1M..4M
  std::vector<std::string> sizes;   // point counts overriding the table's, e.g. 50000 or 1.5M
  int runs = 5;                     // timed runs per backend and workload (median), after one warm-up
  int cgal_runs = 0;                // timed CGAL runs; 0: `runs`
  std::string json_path;            // empty: no JSON
  uint64_t seed = 1;
  bool check = false;               // compare with triangulate_cgal at every size, not only up to 200K points
  bool gpu = true;                  // false (--cgal-only): CGAL column only
  std::string device;               // Vulkan device override, as `cdtgpu devices` lists
  bool ablation = false;            // the paper's Table 3 instead of the tables
  // --table e2e (bench/e2e.hpp): `cdtgpu triangulate` timed as a child process, from files to the written PLY
  std::vector<std::string> backends;  // empty: auto, gpu, cgal, batch (`cdtgpu batch` of batch_jobs auto jobs)
  int batch_jobs = 20;                // jobs in the batch row's job file, each the row's whole run
  std::vector<std::string> formats;   // empty: text, shp
  std::string binary;                 // the cdtgpu to time; empty: this executable (/proc/self/exe)
  std::string keep_dir;               // keep every input, output, stats file and log here; empty: a temp dir
  bool first_run = true;              // the run with empty caches (on lavapipe it compiles every pipeline: ~1 min)
  // --table grid (bench/grid.hpp): CPU and GPU grid and contours of the terrain workload's TIN
  uint64_t grid_cells = 0;            // cells on the grid's long side; 0: 10000 (--quick: 1000)
  // --table peer (bench/peer.hpp)
  std::vector<std::string> rows;      // "POINTS+SEGMENTS" each, e.g. 2M+500K; empty: the five rows
  std::string peer;                   // gDel2D's executable; empty: our columns only
  // --table tiles (bench/tiles.hpp)
  uint64_t tile_points = 0;           // tiles of at most this many points; 0: the CPU's auto size, the GPU's quarter
  bool points_only = false;           // no constraint segments: the Delaunay triangulation tiled
  unsigned tiles_in_flight = 2;        // GPU tiles worked on at once, per device
  std::vector<unsigned> tile_ramps;    // GPU tiles: a row for each TileOptions::ramp (empty: none)
  bool in_runs = false;                // GPU tiles: the order left in the tiles' runs (TileOptions::in_runs)
  std::string devices;                // "all" or "0,1": GPU tiled rows on 2, 4, ... of these devices too (issue 29)
  // Every table: no CGAL run (and so no comparison) for inputs of more points than this; CGAL takes minutes there.
  uint64_t cgal_max_points = 10000000;
};

// Adds the options above to a `bench` subcommand.
void add_bench_options(CLI::App* cmd, BenchOptions& options);

// Returns the exit code: 0, or 1 when a backend's triangles differ from the reference CGAL backend's.
int run_bench(const BenchOptions& options);

// The CGAL configuration the bench times: Constrained_Delaunay_triangulation_2<Epick, TDS, Exact_predicates_tag>
// (the TDS's vertices carry their index), points spatially sorted then inserted with a hint, constraints
// inserted by vertex handle. total_ms = point insertion (sort included) + constraint insertion.
BackendRun run_cgal_fast(const PreparedInput& prepared);

// Shared by the tables: a --sizes value ("50000", "50K", "1.5M"; UsageError otherwise), the CPU's model name,
// the time now as ISO 8601 UTC.
uint64_t parse_bench_size(const std::string& s);
std::string bench_cpu_model();
std::string bench_utc_now();

}  // namespace cdtgpu
