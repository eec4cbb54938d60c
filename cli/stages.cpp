#include "cli/stages.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <optional>
#include <thread>
#include <utility>

#include <spdlog/spdlog.h>

#include "cli/memory.hpp"
#include "cli/progress.hpp"
#include "core/cdt_cgal.hpp"
#include "core/drape.hpp"
#include "core/error.hpp"
#include "core/hillshade.hpp"
#include "core/regions.hpp"
#include "core/resolve.hpp"
#include "core/touched.hpp"
#include "core/tiles.hpp"
#include "core/tiles_ahead.hpp"
#include "core/timing.hpp"
#include "core/uninit.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/check.hpp"
#include "gpu/devices.hpp"
#include "gpu/tile_triangulator.hpp"
#include "gpu/tin.hpp"
#include "io/atomic_file.hpp"
#include "io/gis_writers.hpp"
#include "io/input_spec.hpp"
#include "io/output_guard.hpp"
#include "io/tiles_dir.hpp"
#include "io/write_png.hpp"

namespace cdtgpu {
namespace {

// Times a stage; a stage over a second gets a progress line on a terminal and a log line even without -v.
template <class F>
auto timed(Job& job, const std::string& name, F&& f) {
  std::optional<Progress> progress;
  if (job.stage_progress) progress.emplace(name);
  auto t0 = std::chrono::steady_clock::now();
  auto finish = [&] {
    progress.reset();
    const double ms = ms_since(t0);
    job.stats.stage_ms.emplace_back(name, ms);
    spdlog::log(ms > 1000 ? spdlog::level::info : spdlog::level::debug, "{}: {:.1f} ms", name, ms);
  };
  if constexpr (std::is_void_v<decltype(f())>) {
    f();
    finish();
  } else {
    auto r = f();
    finish();
    return r;
  }
}

uint64_t point_count(const InputSet& in) {
  uint64_t n = in.points.size();
  for (const Polyline& line : in.lines) n += line.points.size();
  return n;
}

// An MPI rank's GPU counts as picked (as the device index it stood for before the start chose it).
bool hardware_only(const TriangulateOptions& o) {
  return o.backend == "auto" && o.device.empty() && o.rank_gpu < 0;
}

// Why auto left the GPU for the CPU part-way (stats backend_reason, and a warning).
std::string gpu_refused(const gpu::DeviceError& e) {
  return std::string("the GPU could not take this input (") + e.what() +
         "): the CPU backend computes the same triangulation";
}

// The tiled CDT (core/tiles) of a resolved input, its figures in the stats.
// in_flight: tiles worked on at once (0: as many as the cores take; a device's: 2, core/tiles.hpp).
// finalize: the tiles' own (the GPU's, core/tiles.hpp); empty: the host's test.
// Under MPI the other ranks take tiles too, as devices of this process do (core/tile_workers.hpp): the GPU's
// tiles (a finalizer given) at ranks with a GPU, the host's at every rank.
bool mesh_only_written(const Job& job);

TileOptions tile_options(const Job& job, uint64_t tile_points, unsigned in_flight, TileFinalizer finalize,
                         std::function<void(uint64_t)> reserve) {
  TileOptions opt;
  opt.finalize = std::move(finalize);
  opt.reserve = std::move(reserve);
  opt.max_tile_points = tile_points;
  opt.tiles_in_flight = in_flight;
  opt.in_runs = mesh_only_written(job);
  const RankTiles* ranks = job.options.ranks;
  if (!ranks || ranks->rank != 0) return opt;
  const bool gpu = bool(opt.finalize);
  TileWorkers workers = ranks->workers(gpu);
  const unsigned remote = workers.total_slots();
  if (remote == 0) return opt;
  if (!gpu) {
    opt.shape = TileShape::squares;  // what the CPU's tiles take without a finalizer
    opt.finalize = host_finalizer(cgal_tile_triangulator());
  }
  const unsigned local = gpu ? in_flight : std::max(1u, std::thread::hardware_concurrency());
  opt.finalize = with_workers(std::move(opt.finalize), local, std::move(workers));
  if (in_flight) opt.tiles_in_flight = in_flight + remote;
  opt.waiting_threads = remote;
  return opt;
}

void record_tiles(Job& job, const TileStats& ts, uint64_t tile_points);

// A resolved input's tiled CDT, tiles of opt.max_tile_points.
CdtResult triangulate_in_tiles(Job& job, ResolvedInput&& in, const TileOptions& opt,
                               const TileTriangulator& triangulate) {
  const uint64_t tile_points = opt.max_tile_points;
  TileStats ts;
  job.stats.counts["constraint_splits_at_vertices"] = in.split_at_vertices;
  CdtResult r = timed(job, "triangulate: tiles and merge", [&] {
    return triangulate_tiled(std::move(in), opt, triangulate, &ts);
  });
  record_tiles(job, ts, tile_points);
  return r;
}

void record_tiles(Job& job, const TileStats& ts, uint64_t tile_points) {
  job.stats.stage_ms.emplace_back("triangulate: tiles", ts.tiles_ms);
  job.stats.stage_ms.emplace_back("triangulate: merge", ts.merge_ms);
  auto& c = job.stats.counts;
  c["tile_points"] = tile_points;
  c["tiles"] = ts.tiles;
  c["tile_levels"] = ts.levels;
  c["tile_final_triangles"] = ts.final_triangles;
  c["merge_vertices"] = ts.merge_vertices;
  c["merge_segments"] = ts.merge_segments;
  c["merge_triangles"] = ts.merge_triangles;
  spdlog::info("{} tiles of at most {} points in {} level(s): {} triangles final in their tiles, a merge of {} "
               "vertices and {} segments gave {}", ts.tiles, tile_points, ts.levels, ts.final_triangles,
               ts.merge_vertices, ts.merge_segments, ts.merge_triangles);
}

// The CPU backend's tile size for n vertices: --max-tile-points, or auto's (core/tiles' auto_cpu_tile_points).
uint64_t cpu_tile_points(const Job& job, uint64_t n) {
  const int64_t m = job.options.max_tile_points;
  return m >= 0 ? uint64_t(m) : auto_cpu_tile_points(n, std::thread::hardware_concurrency());
}

// Whether the CPU backend triangulates n vertices in one CGAL run: no tiles asked for, or n within one tile.
bool cpu_in_one_piece(const Job& job, uint64_t n) {
  const uint64_t tile = cpu_tile_points(job, n);
  return tile < 3 || n <= tile;
}

// The points in CGAL's structures at once on the CPU backend: a tile a core, or all of them in one piece.
uint64_t cpu_points_in_flight(const Job& job, uint64_t points) {
  const uint64_t cores = std::max(1u, std::thread::hardware_concurrency());
  return cpu_in_one_piece(job, points) ? points : std::min(points, cpu_tile_points(job, points) * cores);
}

// Host bytes a point of this job's `points` may take at the run's peak (cli/memory.hpp): the GPU's figure where
// a device was asked for (auto falling back to the CPU is checked again there), tiled beyond any device's
// tile; else the CPU's.
uint64_t bytes_per_point(const Job& job, const std::vector<InputSpec>& specs, uint64_t points, bool on_cpu = false) {
  const bool regions = job.options.max_edge > 0 ||
                       std::any_of(specs.begin(), specs.end(), [](const InputSpec& s) { return is_region_role(s.role); });
  const bool gpu = !on_cpu && job.options.backend != "cgal" && (job.options.backend == "gpu" || job.start);
  const uint64_t base = !gpu ? host_bytes_per_point_cpu(points, cpu_points_in_flight(job, points))
                        : points > gpu::max_tile_points_of_any_device() ? kHostBytesPerPointGpuTiles
                                                                        : kHostBytesPerPointGpu;
  return base + (regions ? kHostBytesPerPointRegions : 0);
}
std::vector<InputSpec> input_specs(const Job& job) {
  std::vector<InputSpec> specs;
  for (const std::string& arg : job.options.input.inputs) specs.push_back(parse_input_spec(arg));
  return specs;
}

// Whether a boundary or hole input was read: its rings are read again by the regions, after prepare.
bool has_region_inputs(const Job& job) {
  return std::any_of(job.parts.begin(), job.parts.end(), [](const InputPart& p) { return is_region_role(p.role); });
}

// Whether a stage after the triangulation reads the prepared input: the regions (boundary and hole rings,
// --max-edge) and the preview's constraint lines.
bool prepared_read_later(const Job& job) {
  return job.options.max_edge > 0 || !job.options.preview.empty() || has_region_inputs(job);
}

// Whether the mesh's triangles go only to its file (OBJ or PLY) and its counts: no regions or --max-edge, grids,
// contours, preview or --tiles-out read them whole. Such a tiled run leaves them in its tiles' runs
// (TileOptions::in_runs), and the writer reads them there: no copy into one array (24 GB at 1B points).
bool mesh_only_written(const Job& job) {
  const TriangulateOptions& o = job.options;
  return vertices_first(job.write) && !prepared_read_later(job) && o.grid_out.empty() && o.contours_out.empty() &&
         o.tiles_out.empty();
}

// The prepared vertices' storage about to be freed, or handed to a stage that may free it: a mesh file begun
// from it is done reading it first.
void vertices_may_go(Job& job) {
  if (job.mesh_ahead) job.mesh_ahead->wait();
}

// The prepared vertices and segments, once the triangulation needs them no more and no later stage reads them:
// 36 bytes a vertex of a tiled run's peak, beside the resolved copy the tiles read. Their counts are in the stats.
void drop_prepared(Job& job) {
  if (prepared_read_later(job)) return;
  // A mesh file begun from them frees them once written: the triangulation may be done first (at 10^8 points
  // the vertex section takes 2.3-2.6 s at the disk's pace, the GPU's run 1.8-1.9 s).
  if (job.mesh_ahead) job.mesh_ahead->free_after_writing(std::move(job.prepared.vertices));
  free_storage(job.prepared.vertices);
  free_storage(job.prepared.constraints);
  free_storage(job.prepared.constraint_line);
}

// Whether a GPU run of this many vertices is tiled on any device (--max-tile-points below them, or more than a
// device takes; open_tiles_early asks it of the points read, before prepare): its tiles check their own
// constraints and begin at once (core/tiles_ahead.hpp, tiled_cdt_unresolved); the resolve runs only if one has
// something to split, and copies the prepared input only then.
bool tiled_on_any_device(uint64_t vertices, int64_t max_tile_points) {
  return max_tile_points >= 0 ? max_tile_points >= 3 && vertices > uint64_t(max_tile_points)
                              : vertices > gpu::max_tile_points_of_any_device();
}

// resolve_if_needed's result made whole: an unchanged input is the prepared one, moved where no later stage reads
// it.
ResolvedInput filled(Job& job, ResolvedInput&& r) {
  if (!r.unchanged) return std::move(r);
  r.unchanged = false;
  if (prepared_read_later(job)) {
    r.vertices = job.prepared.vertices;
    r.constraints = job.prepared.constraints;
  } else {
    vertices_may_go(job);
    r.vertices = std::move(job.prepared.vertices);
    r.constraints = std::move(job.prepared.constraints);
  }
  return std::move(r);
}

// The prepared vertices and segments moved out for a resolve that takes them (their counts stay in
// job.prepared), the constraints' line numbers freed: for a run where no later stage reads them.
PreparedInput take_prepared(Job& job) {
  vertices_may_go(job);
  PreparedInput taken;
  taken.vertices = std::move(job.prepared.vertices);
  taken.constraints = std::move(job.prepared.constraints);
  free_storage(job.prepared.constraint_line);
  return taken;
}

// The CPU backend: the reference CDT in one piece, or tiles on every core (`--max-tile-points`, or auto: core/tiles'
// auto_cpu_tile_points). Both give the same bytes. `resolved`: the input resolved already (the GPU's tiles
// failed; the prepared input may be gone), tiled here too.
CdtResult triangulate_cpu(Job& job, ResolvedInput* resolved = nullptr) {
  // A run checked at the GPU's bytes a point (auto, a device asked for) takes the CPU's here.
  if (job.start)
    check_host_memory(job.prepared.input_points, bytes_per_point(job, input_specs(job), job.prepared.input_points, true),
                      "read, on the CPU");
  const uint64_t n = resolved ? resolved->vertices.size() : job.prepared.vertices.size();
  const uint64_t tile = cpu_tile_points(job, n);
  if (resolved)
    return triangulate_in_tiles(job, std::move(*resolved), tile_options(job, tile < 3 ? 0 : tile, 0, {}, {}),
                                cgal_tile_triangulator());
  if (cpu_in_one_piece(job, n)) return triangulate_cgal(job.prepared);
  // The prepared input handed to the resolve where nothing reads it later: no copy of it beside round 1.
  ResolvedInput in = timed(job, "triangulate: resolve", [&] {
    return prepared_read_later(job) ? resolve_constraints(job.prepared) : resolve_constraints(take_prepared(job));
  });
  return triangulate_in_tiles(job, std::move(in), tile_options(job, tile, 0, {}, {}), cgal_tile_triangulator());
}

// After a tile too large for its device (gpu::too_large), the tile size to try next: the old one scaled by how
// far over the device's limit the tile went (with a quarter to spare), at most halved; 0 when it is not that kind
// of failure or the tiles are small already (a refusal then is not about their size). A size given is warned of.
uint64_t smaller_tile(const gpu::DeviceError& e, uint64_t tile) {
  constexpr uint64_t kSmallest = 1024;
  if (!gpu::too_large(e) || tile / 2 < kSmallest) return 0;
  double scale = 0.5;
  if (const auto* t = dynamic_cast<const gpu::TooLarge*>(&e); t && t->need > 0 && t->limit > 0)
    scale = std::min(scale, 0.75 * t->limit / t->need);
  const uint64_t smaller = std::max<uint64_t>(kSmallest, uint64_t(double(tile) * scale));
  spdlog::warn("{}: again in tiles of at most {} points", e.what(), smaller);
  return smaller;
}

// The GPU's tile size: `--max-tile-points`, or auto: tiles only for an input beyond what the device holds.
uint64_t gpu_tile_points(const gpu::Context& ctx, uint64_t vertices, int64_t max_tile_points) {
  if (max_tile_points >= 0) return uint64_t(max_tile_points);
  const uint64_t limit = gpu::max_tile_points(ctx);
  return vertices > limit ? limit : 0;
}

// The devices a tiled GPU run spreads over (issue 29): those of --devices (default: every hardware GPU of the
// host; the started device alone when it is lavapipe or an MPI rank's own), the started device's context and
// pipelines reused.
gpu::TileDevices tile_devices(const TriangulateOptions& options, const gpu::Context& started,
                              const gpu::GpuCdt& cdt) {
  const std::string& devices = options.devices;
  const bool hardware = started.info.type == "discrete" || started.info.type == "integrated";
  std::vector<size_t> picked = {started.info.index};
  if (options.rank_gpu < 0 && (!devices.empty() || hardware))
    picked = gpu::select_devices(gpu::list_devices(), devices.empty() ? "all" : devices);
  gpu::TileDevices d;
  const auto started_one = std::find(picked.begin(), picked.end(), size_t(started.info.index));
  if (started_one != picked.end()) {
    d.borrow(cdt);
    picked.erase(started_one);
  }
  d.open(picked, gpu::ContextOptions{});
  return d;
}

// Device memory pools for the tiles, unless another rank may take the same GPU (as GpuStarts::device_pool):
// GPUs named under MPI, or a rank's own GPU that its start found shared.
bool tile_pools(const TriangulateOptions& options, const gpu::Context& started) {
  return !options.devices_shared && !started.shared;
}

void record_tile_devices(Job& job, const gpu::TileDevices& d) {
  job.stats.counts["tile_devices"] = d.cdts().size();
  if (d.cdts().size() > 1 || d.cdts().front() != &job.start->cdt()) {
    job.stats.device = d.names();
    spdlog::info("tiles on {} device(s): {}", d.cdts().size(), d.names());
  }
}

// The GPU run's settings of the started device (its Delaunay build's start, whether its buffers stay).
void configure_cdt(const Job& job, gpu::GpuCdt& cdt) {
  cdt.keep_buffers = job.keep_device_buffers;
  cdt.delaunay().initial_dt = job.options.initial_dt == "voronoi" ? gpu::DelaunayBuilder::Start::voronoi
                                                                  : gpu::DelaunayBuilder::Start::insertion;
}

// A tiled run's devices and staging, made ahead (open_tiles_early).
struct TilesAhead {
  std::shared_ptr<gpu::TileDevices> devices;
  std::shared_ptr<gpu::GpuTiles> tiles;
};

// The GPU backend on a started device, the CPU's resolve stage running on other threads meanwhile.
// `ahead`: tiles of the prepared input that check themselves; the resolve (resolve_if_needed's, deferred) only if
// they find something to split (tiled_on_any_device).
CdtResult triangulate_gpu(Job& job, std::future<ResolvedInput>& resolving, const ResolveProgress& progress,
                          const double& resolve_ms, bool ahead) {
  const uint64_t vertices = job.prepared.vertices.size();
  RunStats& stats = job.stats;
  GpuStart& start = *job.start;
  gpu::GpuCdt& cdt = start.cdt();
  if (!job.tiles_ahead) configure_cdt(job, cdt);  // else set before the tiles' warm-up began
  stats.stage_ms.emplace_back("gpu start: context (own thread)", start.context_ms);
  stats.stage_ms.emplace_back("gpu start: pipelines queued (own thread)", start.pipelines_ms);
  stats.stage_ms.emplace_back("gpu start: staging memory (own thread)", start.staging_ms);
  stats.device = start.context().info.name;
  spdlog::debug("device: {} ({} {})", stats.device, start.context().info.driver_name,
                start.context().info.driver_info);
  // With the GPU backend, grids (and the preview's grid) and contour lines are made on the GPU too, with the
  // CPU's values bit for bit. Their pipelines are asked for now, so they compile while the CDT runs.
  const TriangulateOptions& options = job.options;
  if (!options.grid_out.empty() || !options.preview.empty()) job.gpu_raster.emplace(start.context(), cdt.primitives());
  if (!options.contours_out.empty()) job.gpu_contours.emplace(start.context(), cdt.primitives());
  // Called in a DeviceError's handler. Auto: the CPU computes the same triangulation (a device too small for
  // the input, or out of memory); a forced GPU rethrows.
  // `resolved`: the tiles' input, intact when they fail (triangulate_tiled moves from it only once done).
  auto on_cpu_instead = [&](const gpu::DeviceError& e, ResolvedInput* resolved = nullptr) {
    if (options.backend == "gpu") throw;
    stats.backend = "cgal";
    stats.backend_reason = gpu_refused(e);
    spdlog::warn("{}", stats.backend_reason);
    job.gpu = false;
    job.gpu_raster.reset();
    job.gpu_contours.reset();
    return triangulate_cpu(job, resolved);
  };
  // GPU tiles of at most `tile_here` points, tiled again smaller while a tile is more than its device holds;
  // `retries`: such restarts before this call. `resolve` gives the input once the tile devices are open and
  // their staging is being pinned (seconds at 10^8 points, hidden behind the resolve).
  auto in_tiles = [&](const std::function<ResolvedInput()>& resolve, uint64_t tile_here,
                      uint64_t retries) -> CdtResult {
    std::optional<ResolvedInput> got;
    auto input = [&]() -> ResolvedInput& {
      if (!got) {
        got.emplace(resolve());
        drop_prepared(job);
      }
      return *got;
    };
    // The devices opened here and the tiles' staging, closed beside the outputs' writing however this ends.
    std::shared_ptr<gpu::TileDevices> opened;
    std::shared_ptr<gpu::GpuTiles> staged;
    struct CloseLater {
      GpuStart& start;
      std::shared_ptr<gpu::TileDevices>& devices;
      std::shared_ptr<gpu::GpuTiles>& tiles;
      ~CloseLater() {
        start.close_later([d = std::move(devices), t = std::move(tiles)]() mutable {
          t.reset();  // the staging, on the devices' contexts, first
          d.reset();
        });
      }
    } close_later{start, opened, staged};
    try {
      std::shared_ptr<TilesAhead> ahead = timed(job, "gpu start: tile devices", [&] {
        auto made = std::static_pointer_cast<TilesAhead>(start.take_ahead());
        opened = made ? made->devices
                      : std::make_shared<gpu::TileDevices>(tile_devices(options, start.context(), cdt));
        return made;
      });
      record_tile_devices(job, *opened);
      const gpu::TileDevices& devices = *opened;
      if (options.max_tile_points < 0)  // rank 0 of an MPI run waits here for the other ranks' devices
        tile_here = std::min(tile_here, auto_gpu_tile_points(vertices, devices.max_tile_points(),
                                                             run_gpu_devices(devices.cdts().size(), options.ranks)));
      for (;; ++retries) {
        try {
          const bool pools = tile_pools(options, start.context());
          staged = ahead && ahead->tiles
                       ? std::move(ahead->tiles)
                       : std::make_shared<gpu::GpuTiles>(gpu::gpu_tiles(devices.cdts(), nullptr, pools));
          gpu::GpuTiles& tiles = *staged;
          if (!got) tiles.reserve(tile_staging_points(vertices, tile_here));
          auto gpu_options = [&] {
            TileOptions opt =
                tile_options(job, tile_here, unsigned(2 * devices.cdts().size()), tiles.finalize, tiles.reserve);
            opt.ramp = gpu::tile_ramp(devices.cdts(), tile_here);
            opt.tiles_done = tiles.tiles_done;
            return opt;
          };
          if (ahead && !got) {  // the prepared input's tiles; an input they find unresolved, tiled again below
            const TileOptions opt = gpu_options();
            TileStats ts;
            std::optional<OrderedRuns> t = timed(job, "triangulate: tiles and merge", [&] {
              return tiled_cdt_unresolved(job.prepared, opt, tiles.triangulate, &ts);
            });
            if (t) {  // no resolve ran: the prepared vertices are the resolved ones (tiles split segments at them)
              CdtResult r;  // their storage moved (not freed: a mesh file may be begun from it)
              r.mesh.vertices = prepared_read_later(job) ? job.prepared.vertices : std::move(job.prepared.vertices);
              drop_prepared(job);
              if (opt.in_runs)
                r.in_runs = std::move(*t);
              else
                r.mesh.triangles = std::move(*t).take();
              record_tiles(job, ts, tile_here);
              stats.counts["constraint_splits_at_vertices"] = ts.split_at_vertices;
              stats.counts["gpu_tile_retries"] = retries;
              return r;
            }
          }
          CdtResult r = triangulate_in_tiles(job, std::move(input()), gpu_options(), tiles.triangulate);
          stats.counts["gpu_tile_retries"] = retries;
          return r;
        } catch (const gpu::DeviceError& e) {
          // Tiles are sized by points, but a tile's constraint work grows with how many triangles its segments
          // cross (long breaklines over dense LiDAR: 34 a segment), and its tables may not fit then. Smaller
          // tiles (still at most --max-tile-points) do; the same bytes. The input is whole after a failed tiling.
          const uint64_t smaller = smaller_tile(e, tile_here);
          if (!smaller) throw;
          for (const gpu::GpuCdt* c : devices.cdts()) c->drop_kept();
          tile_here = smaller;
        }
      }
    } catch (const gpu::DeviceError& e) {
      return on_cpu_instead(e, &input());
    }
  };
  const uint64_t tile = gpu_tile_points(start.context(), vertices, options.max_tile_points);
  if (ahead || (tile >= 3 && vertices > tile)) {  // ahead: the resolve's result is for tiles only
    return in_tiles(
        [&] {
          ResolvedInput in = timed(job, "triangulate: resolve wait", [&] { return filled(job, resolving.get()); });
          stats.stage_ms.emplace_back("triangulate: resolve (other threads)", resolve_ms);
          return in;
        },
        tile, 0);
  }
  gpu::GpuCdtStats gs;
  CdtResult r;
  try {
    r = cdt.triangulate(job.prepared, std::move(resolving), &gs, &progress);
  } catch (const gpu::DeviceError& e) {
    // The whole input more than the device holds (the tables of long constraints, say): its tiles may fit,
    // unless --max-tile-points 0 forbids them. The resolved input went with the failed call: resolved again.
    if (const uint64_t smaller = options.max_tile_points != 0 ? smaller_tile(e, vertices) : 0) {
      cdt.drop_kept();
      return in_tiles([&] { return timed(job, "triangulate: resolve", [&] { return resolve_constraints(job.prepared); }); },
                      smaller, 1);
    }
    return on_cpu_instead(e);
  }
  stats.stage_ms.emplace_back("triangulate: resolve (other threads)", resolve_ms);
  for (const auto& [name, ms] : gs.wall_ms) stats.stage_ms.emplace_back("triangulate: " + name, ms);
  auto& g = stats.gpu_stage_ms;
  for (const auto& [name, ms] : gs.gpu_ms) g[name] = (g.contains(name) ? g[name].get<double>() : 0.0) + ms;
  g["total"] = gs.gpu_total_ms;
  for (const auto& [name, ms] : gs.gpu_ms) spdlog::debug("gpu {}: {:.3f} ms", name, ms);
  spdlog::debug("gpu total {:.2f} ms, peak device memory {} bytes", gs.gpu_total_ms, gs.peak_device_bytes);
  stats.counts["constraint_splits_at_vertices"] = gs.split_at_vertices;
  stats.counts["gpu_delaunay_rounds"] = gs.delaunay.rounds;
  stats.counts["gpu_delaunay_built_twice"] = gs.delaunay_built_twice;
  stats.counts["gpu_constraint_flip_rounds"] = gs.constraints.flip_rounds;
  stats.counts["gpu_legalise_rounds"] = gs.constraints.legalise_rounds;
  stats.counts["gpu_peak_device_bytes"] = gs.peak_device_bytes;
  return r;
}

// A .prj beside a device, FIFO or /dev/stdout makes no sense (it would be /dev/stdout.prj): the CRS name in the
// stream is all such an output gets.
Crs crs_for(const Job& job, const std::string& path) {
  Crs c = job.crs;
  if (is_special_output(path)) c.wkt.clear();
  return c;
}

// LAS inputs: points kept and skipped per class, and why (--stats; a log line when any was skipped).
void add_point_class_counts(const PointClassCounts& pc, RunStats& stats) {
  if (!pc.any) return;
  nlohmann::ordered_json by_class = nlohmann::ordered_json::object();
  for (const auto& [cls, n] : pc.by_class) by_class[std::to_string(cls)] = {{"kept", n.kept}, {"skipped", n.skipped}};
  stats.counts["las_points_by_class"] = by_class;
  stats.counts["las_skipped_withheld"] = pc.withheld;
  stats.counts["las_skipped_returns"] = pc.other_returns;
  stats.counts["las_skipped_classes"] = pc.other_classes;
  if (pc.withheld + pc.other_returns + pc.other_classes)
    spdlog::info("LAS points skipped: {} withheld, {} of other returns, {} of other classes", pc.withheld,
                 pc.other_returns, pc.other_classes);
}

}  // namespace

void check_job(Job& job) {
  const TriangulateOptions& options = job.options;
  job.write = options.write;
  if (options.output.empty() && options.tiles_out.empty())
    throw UsageError("no output: give -o FILE (or - for stdout) and/or --tiles-out DIR");
  if (!options.format.empty())
    job.write.format = parse_format(options.format);
  else if (options.output == "-")
    throw UsageError("writing to stdout needs --format (obj, ply, wkt, landxml or 2dm)");
  else if (!options.output.empty())
    job.write.format = format_from_extension(options.output);
  if (options.backend != "auto" && options.backend != "gpu" && options.backend != "cgal")
    throw UsageError("unknown backend '" + options.backend + "' (use auto, gpu or cgal)");
  job.outputs = triangulate_outputs(options.output, options.stats_path);
  if (!job.stats_copy.empty()) job.outputs.push_back(job.stats_copy);
  if (!options.tiles_out.empty()) job.outputs.push_back(tiles_dir_path(options.tiles_out));  // checked like a file
  for (const std::string* extra : {&options.grid_out, &options.contours_out, &options.preview})
    if (!extra->empty()) job.outputs.push_back(*extra);  // their .prj files hold the mesh's CRS and may be its .prj
  job.input_paths.clear();
  for (const std::string& arg : options.input.inputs) job.input_paths.push_back(parse_input_spec(arg).path);
  check_outputs_spare_inputs(job.input_paths, job.outputs);
}

// About how many points the files hold (estimate_input_points), asked for by start_gpu_early and read_job and
// made once: it opens every input.
namespace {
uint64_t estimated_points(Job& job) {
  if (!job.estimated_points) job.estimated_points = estimate_input_points(job.input_paths);
  return *job.estimated_points;
}
}  // namespace

// The GPU starts on its own thread while the inputs are read: forced, or when auto may pick it (the files are
// large enough to hold gpus.auto_min_points points).
void start_gpu_early(Job& job, GpuStarts& gpus) {
  const TriangulateOptions& options = job.options;
  const uint64_t estimate = estimated_points(job);
  spdlog::debug("about {} input points in the files", estimate);
  // An MPI worker runs tiles only, each in staging of its own: the start's staging (up to 1 GiB, pinned) would
  // serve a whole run it never makes.
  const bool worker = options.ranks && options.ranks->rank != 0;
  if (options.devices_shared) gpus.device_pool = false;
  gpus.nth_gpu = options.rank_gpu;
  gpus.processes_on_host = options.host_ranks;
  if (options.backend == "gpu" || (options.backend == "auto" && estimate >= gpus.auto_min_points))
    job.start = &gpus.start(options.device, hardware_only(options), worker ? 0 : estimate,
                            tiled_on_any_device(estimate, options.max_tile_points));
}


uint64_t estimated_peak_bytes(Job& job) {
  const uint64_t points = estimated_points(job);
  return points * bytes_per_point(job, input_specs(job), points);
}

// Read and projected; what prepare_job needs next.
void read_job(Job& job) {
  const std::vector<InputSpec> specs = input_specs(job);
  const uint64_t estimate = estimated_points(job);
  check_host_memory(estimate, bytes_per_point(job, specs, estimate), "estimated from the input files");
  timed(job, "read", [&] { job.parts = read_inputs(specs, job.options.input.read, job.in); });
  const uint64_t read = point_count(job.in);
  check_host_memory(read, bytes_per_point(job, specs, read), "read");
  job.crs = timed(job, "crs", [&] { return choose_crs(job.in, job.options.input.crs); });
  timed(job, "project", [&] { project(job.in, job.crs); });
  const DrapeStats drape = timed(job, "drape", [&] { return apply_z_rules(job.in, job.parts); });
  if (drape.draped_vertices)
    spdlog::info("draped {} vertices ({} beyond the surface's hull took the z of its nearest edge)",
                 drape.draped_vertices, drape.outside_surface);
  job.stats.counts["draped_vertices"] = drape.draped_vertices;
  uint64_t zero_z = 0;
  for (size_t i = 0; i < drape.zero_z.size(); ++i)
    if (drape.zero_z[i]) {
      zero_z += drape.zero_z[i];
      spdlog::info("{}: {} vertices have no z and get 0 (:z=drape drapes them, :z=0 says so)", specs[i].path,
                   drape.zero_z[i]);
    }
  job.stats.counts["vertices_without_z"] = zero_z;
}

// Auto: the GPU from gpus.auto_min_points points read. Started now if the files' estimate did not start it, so
// that it overlaps prepare; a device named with --device is used as it is.
void choose_backend(Job& job, GpuStarts& gpus) {
  const TriangulateOptions& options = job.options;
  const uint64_t min_points = gpus.auto_min_points;
  const uint64_t n = point_count(job.in);
  job.backend_reason = "--backend " + options.backend;
  job.want_gpu = options.backend == "gpu";
  if (options.backend == "auto") {
    job.want_gpu = n >= min_points;
    if (!job.want_gpu)
      job.backend_reason = std::to_string(n) + " input points, fewer than " + std::to_string(min_points) +
                           (min_points == auto_min_points() ? ": the CPU is faster than the GPU's start-up"
                                                            : ": the CPU is faster than the GPU on jobs this small");
    else if (!job.start)
      job.start =
          &gpus.start(options.device, hardware_only(options), n, tiled_on_any_device(n, options.max_tile_points));
  }
}

void resolve_early(Job& job) {
  if (!job.want_gpu || tiled_on_any_device(job.prepared.vertices.size(), job.options.max_tile_points)) return;
  const auto t0 = std::chrono::steady_clock::now();
  job.resolved_early = resolve_constraints(job.prepared);
  job.resolved_early_ms = ms_since(t0);
}

GpuStart& gpu_start_on(Job& job, GpuStarts& gpus, const std::string& device, unsigned copy) {
  const uint64_t n = estimated_points(job);
  return gpus.start(device, hardware_only(job.options), n, tiled_on_any_device(n, job.options.max_tile_points), copy);
}

namespace {
// A tiled run's devices (tile_devices) and their staging for tiles of n points, on a started device: rank 0's
// before prepare (open_tiles_early), an MPI worker's before it serves (serve_tiles).
std::shared_ptr<TilesAhead> open_tile_devices(const Job& job, gpu::GpuCdt& cdt, uint64_t n, const char* when) {
  const int64_t m = job.options.max_tile_points;
  configure_cdt(job, cdt);
  auto ahead = std::make_shared<TilesAhead>();
  ahead->devices = std::make_shared<gpu::TileDevices>(tile_devices(job.options, cdt.context(), cdt));
  uint64_t tile = gpu_tile_points(cdt.context(), n, m);
  if (m < 0)
    tile = std::min(tile, auto_gpu_tile_points(n, ahead->devices->max_tile_points(),
                                               expected_gpu_devices(ahead->devices->cdts().size(), job.options.ranks)));
  ahead->tiles = std::make_shared<gpu::GpuTiles>(
      gpu::gpu_tiles(ahead->devices->cdts(), nullptr, tile_pools(job.options, cdt.context())));
  if (tiled_on_any_device(n, m)) ahead->tiles->reserve(tile_staging_points(n, tile));
  spdlog::debug("gpu start: {} tile device(s) opened {}, their staging begun for tiles of {} points",
                ahead->devices->cdts().size(), when, tile);
  return ahead;
}
}  // namespace

// A GPU run whose input is more than a device takes (or than --max-tile-points) opens its tile devices and
// reserves their staging while prepare runs, each device warming up with a tile of the expected size (on
// hardware GPUs): at 1B points the first tile waited ~2 s for its staging, and each device's first tile made
// its buffers. The input's point count stands for its vertices (prepare only merges them); a run that is not
// tiled after all closes them with the device. Not in a batch, whose next job is read beside the device's work.
void open_tiles_early(Job& job) {
  if (!job.want_gpu || !job.start) return;
  const uint64_t n = point_count(job.in);
  if (!tiled_on_any_device(n, job.options.max_tile_points)) return;
  job.tiles_ahead = job.start->begin_ahead([&job, n](gpu::GpuCdt& cdt) {
    return std::shared_ptr<void>(open_tile_devices(job, cdt, n, "before prepare"));
  });
}

// An MPI rank other than 0: its share of the inputs read and sent to rank 0 (if it reads one), then the tiles rank
// 0 hands it, on its GPU (started as rank 0's is, from the files' estimate) or its cores, until rank 0 has no more.
// Its devices and their staging are made before it says what it takes, as open_tiles_early makes rank 0's.
void serve_tiles(Job& job) {
  const TriangulateOptions& options = job.options;
  if (options.input.read.share)  // the first rank of its host (cli/mpi.hpp)
    timed(job, "read (this rank's share, sent to rank 0)",
          [&] { job.parts = read_inputs(input_specs(job), options.input.read, job.in); });
  std::shared_ptr<TilesAhead> gpu;
  if (job.start) try {
      gpu = open_tile_devices(job, job.start->cdt(), estimated_points(job), "before taking tiles");
    } catch (const gpu::DeviceError& e) {
      spdlog::warn("this rank takes no GPU tiles: {}", e.what());
    }
  const unsigned gpu_slots = gpu ? unsigned(2 * gpu->devices->cdts().size()) : 0;
  const TileFinalizer on_host = host_finalizer(cgal_tile_triangulator());
  timed(job, "tiles for rank 0", [&] {
    options.ranks->serve(gpu_slots, std::max(1u, std::thread::hardware_concurrency()),
                         [&](bool on_gpu, const TileJob& tile) { return on_gpu ? gpu->tiles->finalize(tile) : on_host(tile); });
  });
  if (gpu) gpu->tiles.reset();  // the staging, on the devices' contexts, first
}

// The merge stays on the CPU even when the device is ready: on all 16 cores of the H100 machine it took 31-44 ms
// for 2.5M points, the GPU's (gpu/dedupe, the same result) ~59 ms with its transfers.
void prepare_job(Job& job, bool mesh_file_ahead) {
  // Later stages read only the rings of boundary and hole inputs (region_rules): the rest of what was read
  // goes as soon as prepare has copied it. Kept to the end, it was a quarter of a large run's peak (80M
  // vertices in tiles: 3.0 of 13 GB).
  const bool rings = has_region_inputs(job);
  // On all cores: freed on one, the 24 GB of points and 8000 lines of 1B + 250M took seconds of prepare's
  // critical path, between its scatter and its sort.
  auto drop_input = [&] {
    free_storage_on_all_cores(job.in.points);
    if (rings) return;
    tbb::parallel_for(size_t(0), job.in.lines.size(), [&](size_t l) { free_storage(job.in.lines[l].points); });
    free_storage(job.in.lines);
  };
  VerticesAhead ahead;
  if (mesh_file_ahead) {
    ahead.made = [&](const Points& vertices) { begin_mesh_file(job, vertices); };
    ahead.abandoned = [&] { job.mesh_ahead.reset(); };  // waits for its writing, then removes the file
  }
  job.prepared = timed(job, "prepare", [&] { return prepare(job.in, {}, drop_input, ahead); });
  spdlog::info("CRS: {}", job.crs.name);

  const Repairs& r = job.in.repairs;
  const PreparedInput& p = job.prepared;
  if (p.merged_duplicates)
    spdlog::info("merged {} duplicate points into existing vertices", p.merged_duplicates);
  if (p.z_conflicts)
    spdlog::warn("{} merged points had different z (largest difference {}): the first one read was kept",
                 p.z_conflicts, p.max_z_conflict);
  if (p.duplicate_segments) spdlog::info("{} repeated constraint segments counted once", p.duplicate_segments);
  if (r.repeated_vertices) spdlog::info("repaired {} repeated vertices (zero-length segments)", r.repeated_vertices);
  if (r.rings_closed) spdlog::info("closed {} rings that did not end at their first vertex", r.rings_closed);
  if (r.degenerate_lines) spdlog::info("{} lines with a single distinct vertex kept as points", r.degenerate_lines);
  if (r.null_shapes) spdlog::info("skipped {} NULL shapes (no geometry)", r.null_shapes);
  if (r.nodata_cells) spdlog::info("skipped {} NODATA grid cells", r.nodata_cells);

  auto& c = job.stats.counts;
  c["input_points"] = p.input_points;
  c["merged_duplicates"] = p.merged_duplicates;
  c["z_conflicts"] = p.z_conflicts;
  c["input_segments"] = p.input_segments;
  c["duplicate_segments"] = p.duplicate_segments;
  c["constraints"] = p.constraints.size();
  c["repeated_vertices_removed"] = r.repeated_vertices;
  c["rings_closed"] = r.rings_closed;
  c["degenerate_lines"] = r.degenerate_lines;
  c["null_shapes"] = r.null_shapes;
  c["nodata_cells"] = r.nodata_cells;
  add_point_class_counts(job.in.point_classes, job.stats);
  job.stats.crs = job.crs.name;
  job.stats.crs_epsg = job.crs.epsg;
}

void begin_mesh_file(Job& job, const Points& vertices) {
  const TriangulateOptions& o = job.options;
  if (o.output.empty() || o.max_edge > 0 || has_region_inputs(job)) return;
  job.mesh_ahead = std::make_unique<MeshFileAhead>(o.output, crs_for(job, o.output), job.write, vertices);
  if (!job.mesh_ahead->begun()) job.mesh_ahead.reset();
}

// The GPU is waited for as late as possible, so that its start (~160 ms on the H100 machine) overlaps the CPU's
// work: reading, the duplicate merge and resolving the constraints. Auto falls back to the CPU when the start
// fails or the device refuses the input; a forced GPU throws.
void triangulate_job(Job& job) {
  RunStats& stats = job.stats;
  stats.backend = "cgal";
  // The GPU path's CPU resolve stage starts now, on other threads, beside the device's start and then the
  // Delaunay build (gpu::GpuCdt::triangulate waits for it where it needs the constraints).
  double resolve_ms = 0;
  ResolveProgress progress;
  const uint64_t vertices = job.prepared.vertices.size();
  const bool ahead = job.want_gpu && tiled_on_any_device(vertices, job.options.max_tile_points);
  // Declared after what its task reads: a throw before get() waits for the task before those go. Tiles that
  // check themselves: run only if one has something to split (or the device fails them).
  std::future<ResolvedInput> resolving;
  if (job.want_gpu && job.resolved_early) {
    resolve_ms = job.resolved_early_ms;
    resolving = std::async(std::launch::deferred, [&] {
      ResolvedInput r = std::move(*job.resolved_early);
      job.resolved_early.reset();
      return r;
    });
  } else if (job.want_gpu) {
    resolving = std::async(ahead ? std::launch::deferred : std::launch::async, [&] {
      const auto t0 = std::chrono::steady_clock::now();
      // Tiles that found something to split read the prepared input no more: where no later stage does, the
      // resolve takes it (at 1B points a copy beside it was 30 GB and 2.5 s).
      ResolvedInput r = !ahead                      ? resolve_constraints(job.prepared, progress)
                        : prepared_read_later(job) ? resolve_if_needed(job.prepared)
                                                   : resolve_constraints(take_prepared(job));
      resolve_ms = ms_since(t0);
      return r;
    });
  }
  job.result = timed(job, "triangulate", [&] {
    if (job.want_gpu) {
      timed(job, "triangulate: gpu start wait", [&] {
        try {
          job.start->cdt();
          job.gpu = true;
          if (job.options.backend == "auto")
            job.backend_reason = std::to_string(job.prepared.input_points) + " input points on a GPU";
        } catch (const gpu::DeviceError& e) {
          if (job.options.backend == "gpu") throw;
          job.backend_reason = std::string("no GPU to use (") + e.what() + ")";
        }
      });
    }
    stats.backend = job.gpu ? "gpu" : "cgal";
    stats.backend_reason = job.backend_reason;
    spdlog::debug("backend {}: {}", stats.backend, job.backend_reason);
    if (job.gpu) return triangulate_gpu(job, resolving, progress, resolve_ms, ahead);
    if (!job.want_gpu) return triangulate_cpu(job);
    // No device after all. The resolve begun for it reads the prepared input, which the CPU's tiles free: its
    // result is what they tile (a second resolve beside it freed the input under it). One CGAL run waits for it.
    ResolvedInput in = filled(job, resolving.get());
    stats.stage_ms.emplace_back("triangulate: resolve (other threads)", resolve_ms);
    if (!ahead && cpu_in_one_piece(job, vertices)) return triangulate_cpu(job);
    return triangulate_cpu(job, &in);
  });
  // The tiles leave the triangles in their runs only for a job whose mesh is only written (tile_options): every
  // other reader (regions, grids, contours, preview, --tiles-out) gets one array.
  if (!mesh_only_written(job)) gather_triangles(job.result);
  drop_prepared(job);
}

void apply_job_regions(Job& job) {
  const RegionRules rules = region_rules(job.in, job.parts, job.prepared, job.options.max_edge);
  if (const OpenEnds open = open_region_ends(job.prepared, rules); open.count)
    spdlog::warn("{}: their regions leak (docs/rules.md, \"Regions\")", open_ends_text(job.prepared, open));
  const RegionStats rs = timed(job, "regions", [&] { return apply_regions(job.result.mesh, job.prepared, rules); });
  if (rs.triangles_outside || rs.triangles_trimmed)
    spdlog::info("dropped {} triangles outside boundaries or inside holes, {} by --max-edge", rs.triangles_outside,
                 rs.triangles_trimmed);
  job.stats.counts["triangles_outside_regions"] = rs.triangles_outside;
  job.stats.counts["triangles_trimmed"] = rs.triangles_trimmed;
  job.stats.counts["vertices_outside_regions"] = rs.vertices_removed;
  if (job.result.mesh.triangles.empty() && job.result.in_runs.empty())
    spdlog::warn(rs.triangles_outside || rs.triangles_trimmed
                     ? "no triangles: boundaries, holes and --max-edge dropped them all"
                     : "no triangles: fewer than 3 distinct points, or all points collinear");
}

// Derived outputs are computed before anything is written: a grid that cannot be made writes nothing. The
// device's part ends here (its buffers are freed), so that a batch writes this job while the next one runs there.
void derive_outputs(Job& job) {
  const TriangulateOptions& options = job.options;
  const Mesh& mesh = job.result.mesh;
  std::optional<gpu::DeviceTin> tin;  // the final mesh on the device, uploaded once for all of them
  auto device_tin = [&]() -> const gpu::DeviceTin& {
    if (!tin) tin = timed(job, "tin upload", [&] { return gpu::upload_tin(job.start->context(), mesh); });
    return *tin;
  };
  // A device that cannot hold the work (a mesh or a grid row beyond its buffer range) leaves it to the CPU,
  // whose result is the same.
  auto on_cpu = [&](const gpu::DeviceError& e, const char* what) {
    spdlog::warn("{} on the CPU: {}", what, e.what());
    job.stats.stage_ms.emplace_back(std::string(what) + ": on the CPU after a device refusal", 0.0);
  };
  auto grid_of = [&](double cell, const char* name) {
    const GridSpec spec = grid_for(mesh, cell);
    if (job.gpu_raster) try {
        Raster r = job.gpu_raster->rasterise(device_tin(), spec);
        job.stats.gpu_stage_ms[name] = job.gpu_raster->gpu_ms;
        return r;
      } catch (const gpu::DeviceError& e) {
        on_cpu(e, name);
      }
    return rasterise(mesh, spec);
  };
  if (!options.grid_out.empty()) job.grid = timed(job, "grid", [&] { return grid_of(options.cell, "grid"); });
  if (!options.contours_out.empty())
    job.contours = timed(job, "contours", [&] {
      if (job.gpu_contours) try {
          std::vector<Contour> lines = job.gpu_contours->lines(device_tin(), mesh, options.interval);
          job.stats.gpu_stage_ms["contours"] = job.gpu_contours->gpu_ms;
          job.stats.stage_ms.emplace_back("contours: host sort and chaining", job.gpu_contours->chain_ms);
          return lines;
        } catch (const gpu::DeviceError& e) {
          on_cpu(e, "contours");
        }
      return contour_lines(mesh, options.interval);
    });
  if (!options.preview.empty())
    job.preview = timed(job, "preview", [&] { return grid_of(preview_cell(mesh, 1000), "preview"); });
  tin.reset();
  job.gpu_raster.reset();
  job.gpu_contours.reset();
}

namespace {

// The mesh file and the --tiles-out folder; returns how many tile files. Touches no stats: it may run on a
// thread of its own beside derive_outputs.
uint64_t write_mesh_files(const Job& job) {
  const TriangulateOptions& options = job.options;
  // A file begun ahead is finished where the mesh has the prepared vertices: the run added none (prepare's
  // vertices are canonical, a resolve only adds Steiner vertices) and dropped none (no regions, begin_mesh_file).
  const CdtResult& r = job.result;
  const TriangleSpans one(r.mesh.triangles);
  const TriangleSpans& triangles = r.in_runs.empty() ? one : r.in_runs.spans();  // mesh_only_written
  const bool ahead = job.mesh_ahead && job.mesh_ahead->finish(r.mesh.vertices.size(), triangles, r.steiner_points == 0);
  if (!options.output.empty() && !ahead) {
    if (r.in_runs.empty())
      write_mesh_file(r.mesh, crs_for(job, options.output), job.write, options.output);
    else
      write_mesh_file(r.mesh.vertices, triangles, crs_for(job, options.output), job.write, options.output);
  }
  if (options.tiles_out.empty()) return 0;
  // Pieces as large as the run's tiles, else a million points a file.
  const uint64_t piece = options.max_tile_points > 0 ? uint64_t(options.max_tile_points) : 1'000'000;
  const std::vector<MeshPiece> pieces = split_mesh(job.result.mesh, piece);
  write_tiles_dir(pieces, job.crs, job.write, options.tiles_out, options.tiles_sharing);
  return pieces.size();
}

void write_derived_files(Job& job) {
  const TriangulateOptions& options = job.options;
  if (job.grid) write_grid_file(*job.grid, crs_for(job, options.grid_out), options.grid_out);
  if (!options.contours_out.empty())
    write_contours_wkt_file(job.contours, crs_for(job, options.contours_out), options.contours_out);
  if (job.preview) {
    std::vector<uint8_t> rgba = hillshade_rgba(*job.preview);
    draw_edges(rgba, job.preview->spec, job.prepared.vertices, job.prepared.constraints);
    write_png_file(options.preview, job.preview->spec.ncols, job.preview->spec.nrows, rgba);
  }
}

}  // namespace

void write_outputs(Job& job) {
  timed(job, "write", [&] {
    const uint64_t tile_files = write_mesh_files(job);
    if (!job.options.tiles_out.empty()) job.stats.counts["tile_files"] = tile_files;
    write_derived_files(job);
  });
}

void derive_and_write_outputs(Job& job, const std::function<void()>& device_done) {
  const TriangulateOptions& options = job.options;
  if (options.grid_out.empty() && options.contours_out.empty() && options.preview.empty()) {
    if (device_done) device_done();
    write_outputs(job);
    return;
  }
  // The mesh is final: it is written while the grid, contours and preview are made from it. A grid the
  // options cannot make is a usage error before anything is written; a later failure of either side leaves
  // the other's files whole (each is written atomically), as a failing grid write always did.
  if (!options.grid_out.empty()) grid_for(job.result.mesh, options.cell);
  double mesh_ms = 0;
  std::future<uint64_t> mesh = std::async(std::launch::async, [&] {
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t files = write_mesh_files(job);
    mesh_ms = ms_since(t0);
    return files;
  });
  try {
    derive_outputs(job);
  } catch (...) {
    mesh.wait();
    throw;
  }
  if (device_done) device_done();
  timed(job, "write", [&] {
    const uint64_t tile_files = mesh.get();
    if (!options.tiles_out.empty()) job.stats.counts["tile_files"] = tile_files;
    write_derived_files(job);
  });
  job.stats.stage_ms.emplace_back("write: mesh (own thread, beside the derived outputs)", mesh_ms);
}

void count_results(Job& job) {
  auto& c = job.stats.counts;
  const CdtResult& result = job.result;
  if (job.grid) c["grid_cells"] = job.grid->z.size();
  if (!job.options.contours_out.empty()) c["contour_lines"] = job.contours.size();
  c["steiner_points"] = result.steiner_points;
  if (job.mesh_ahead)
    job.stats.stage_ms.emplace_back("write: mesh vertices, begun ahead (own thread)", job.mesh_ahead->vertices_ms());
  c["vertices"] = result.mesh.vertices.size();
  c["triangles"] = result.mesh.triangles.size() + result.in_runs.size();
  job.stats.peak_host_bytes = peak_host_bytes();  // the process's: in a batch, the largest job's so far
  spdlog::info("{} vertices, {} triangles ({} constraints, {} Steiner points)", result.mesh.vertices.size(),
               c["triangles"].get<uint64_t>(), c["constraints"].get<uint64_t>(), result.steiner_points);
  if (job.gpu) {
    // Both are the process's totals: in a batch, every job's so far.
    job.stats.stage_ms.emplace_back("triangulate: pipeline waits", gpu::pipeline_wait_ms());
    job.stats.stage_ms.emplace_back("gpu: memory allocation and release (all threads)", gpu::memory_ms());
    spdlog::debug("gpu memory allocation and release: {:.1f} ms (all threads)", gpu::memory_ms());
  }
}

void release_job(Job& job, GpuStarts* exiting) {
  timed(job, "release", [&] {
    if (exiting) exiting->leave_for_exit();
    job.mesh_ahead.reset();  // a file not finished (no output was written): removed
    job.in = InputSet{};
    free_storage(job.parts);
    job.prepared = PreparedInput{};
    job.result = CdtResult{};
    job.grid.reset();
    job.preview.reset();
    free_storage(job.contours);
  });
}

void write_job_stats(const Job& job) {
  for (const std::string* path : {&job.options.stats_path, &job.stats_copy})
    if (!path->empty())
      write_file_atomically(*path, [&](std::ostream& out) { out << job.stats.to_json().dump(2) << '\n'; });
}

}  // namespace cdtgpu
