#include "cli/run.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <optional>
#include <span>
#include <thread>

#include <spdlog/spdlog.h>

#include "core/cdt_cgal.hpp"
#include "core/drape.hpp"
#include "core/error.hpp"
#include "core/hillshade.hpp"
#include "core/prepare.hpp"
#include "core/regions.hpp"
#include "core/resolve.hpp"
#include "core/stats.hpp"
#include "core/tiles.hpp"
#include "core/verify.hpp"
#include "cli/gpu_start.hpp"
#include "cli/progress.hpp"
#include "core/verify_regions.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/check.hpp"
#include "gpu/contours.hpp"
#include "gpu/raster.hpp"
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
auto timed(RunStats& stats, const std::string& name, F&& f) {
  Progress progress(name);
  auto t0 = std::chrono::steady_clock::now();
  auto finish = [&] {
    progress.stop();
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    stats.stage_ms.emplace_back(name, ms);
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

struct Loaded {
  InputSet in;
  std::vector<InputPart> parts;  // what each input added, with its role and z rule
  Crs crs;
  PreparedInput prepared;
};

// Read and projected; what prepare() needs next.
Loaded read_all(const InputOptions& options, RunStats& stats) {
  Loaded l;
  std::vector<InputSpec> specs;
  for (const std::string& arg : options.inputs) specs.push_back(parse_input_spec(arg));
  timed(stats, "read", [&] { l.parts = read_inputs(specs, options.read, l.in); });
  l.crs = choose_crs(l.in, options.crs);
  timed(stats, "project", [&] { project(l.in, l.crs); });
  const DrapeStats drape = timed(stats, "drape", [&] { return apply_z_rules(l.in, l.parts); });
  if (drape.draped_vertices)
    spdlog::info("draped {} vertices ({} beyond the surface's hull took the z of its nearest edge)",
                 drape.draped_vertices, drape.outside_surface);
  stats.counts["draped_vertices"] = drape.draped_vertices;
  uint64_t zero_z = 0;
  for (size_t i = 0; i < drape.zero_z.size(); ++i)
    if (drape.zero_z[i]) {
      zero_z += drape.zero_z[i];
      spdlog::info("{}: {} vertices have no z and get 0 (:z=drape drapes them, :z=0 says so)", specs[i].path,
                   drape.zero_z[i]);
    }
  stats.counts["vertices_without_z"] = zero_z;
  return l;
}

uint64_t point_count(const InputSet& in) {
  uint64_t n = in.points.size();
  for (const Polyline& line : in.lines) n += line.points.size();
  return n;
}

// LAS inputs' points per class, kept and skipped by their filters (io/read_las.hpp).
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

// `merge`: the duplicate merging of prepare (the CPU's by default; the GPU backend passes its own).
void prepare_all(Loaded& l, RunStats& stats, const PointMerger& merge = merge_points) {
  l.prepared = timed(stats, "prepare", [&] { return prepare(l.in, merge); });
  spdlog::info("CRS: {}", l.crs.name);

  const Repairs& r = l.in.repairs;
  const PreparedInput& p = l.prepared;
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

  auto& c = stats.counts;
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
  add_point_class_counts(l.in.point_classes, stats);
  stats.crs = l.crs.name;
  stats.crs_epsg = l.crs.epsg;
}


Loaded load(const InputOptions& options, RunStats& stats) {
  Loaded l = read_all(options, stats);
  prepare_all(l, stats);
  return l;
}

void write_stats(const RunStats& stats, const std::string& path) {
  if (path.empty()) return;
  write_file_atomically(path, [&](std::ostream& out) { out << stats.to_json().dump(2) << '\n'; });
}

// Why auto left the GPU for the CPU part-way (stats backend_reason, and a warning).
std::string gpu_refused(const gpu::DeviceError& e) {
  return std::string("the GPU could not take this input (") + e.what() +
         "): the CPU backend computes the same triangulation";
}

// The tiled CDT (core/tiles) of a resolved input, its figures in the stats.
// in_flight: tiles worked on at once (0: as many as the cores take; a device's: 2, core/tiles.hpp).
CdtResult triangulate_in_tiles(ResolvedInput&& in, uint64_t tile_points, const TileTriangulator& triangulate,
                               RunStats& stats, unsigned in_flight = 0) {
  TileOptions opt;
  opt.max_tile_points = tile_points;
  opt.tiles_in_flight = in_flight;
  TileStats ts;
  CdtResult r = timed(stats, "triangulate: tiles and merge", [&] {
    return triangulate_tiled(std::move(in), opt, triangulate, &ts);
  });
  stats.stage_ms.emplace_back("triangulate: tiles", ts.tiles_ms);
  stats.stage_ms.emplace_back("triangulate: merge", ts.merge_ms);
  auto& c = stats.counts;
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
  return r;
}

// The CPU backend: the reference CDT in one piece, or tiles on every core (`--max-tile-points`, or auto: core/tiles'
// auto_cpu_tile_points). Both give the same bytes.
CdtResult triangulate_cpu(const PreparedInput& prepared, int64_t max_tile_points, RunStats& stats) {
  const uint64_t n = prepared.vertices.size();
  const uint64_t tile = max_tile_points >= 0 ? uint64_t(max_tile_points)
                                             : auto_cpu_tile_points(n, std::thread::hardware_concurrency());
  if (tile < 3 || n <= tile) return triangulate_cgal(prepared);
  ResolvedInput in = timed(stats, "triangulate: resolve", [&] { return resolve_constraints(prepared); });
  return triangulate_in_tiles(std::move(in), tile, cgal_tile_triangulator(), stats);
}

// The GPU's tile size: `--max-tile-points`, or auto: tiles only for an input beyond what the device holds.
uint64_t gpu_tile_points(const gpu::Context& ctx, uint64_t vertices, int64_t max_tile_points) {
  if (max_tile_points >= 0) return uint64_t(max_tile_points);
  const uint64_t limit = gpu::max_tile_points(ctx);
  return vertices > limit ? limit : 0;
}

}  // namespace

int run_triangulate(const TriangulateOptions& options) {
  RunStats stats;
  WriteOptions write = options.write;
  if (options.output.empty() && options.tiles_out.empty())
    throw UsageError("no output: give -o FILE (or - for stdout) and/or --tiles-out DIR");
  if (!options.format.empty())
    write.format = parse_format(options.format);
  else if (options.output == "-")
    throw UsageError("writing to stdout needs --format (obj, ply, wkt, landxml or 2dm)");
  else if (!options.output.empty())
    write.format = format_from_extension(options.output);
  if (options.backend != "auto" && options.backend != "gpu" && options.backend != "cgal")
    throw UsageError("unknown backend '" + options.backend + "' (use auto, gpu or cgal)");
  std::vector<std::string> outputs = triangulate_outputs(options.output, options.stats_path);
  if (!options.tiles_out.empty()) outputs.push_back(tiles_dir_path(options.tiles_out));  // checked like a file
  for (const std::string* extra : {&options.grid_out, &options.contours_out, &options.preview})
    if (!extra->empty()) outputs.push_back(*extra);  // their .prj files hold the mesh's CRS and may be its .prj
  std::vector<std::string> input_paths;  // without their :key=value options
  for (const std::string& arg : options.input.inputs) input_paths.push_back(parse_input_spec(arg).path);
  check_outputs_spare_inputs(input_paths, outputs);

  // The GPU starts on its own thread while the inputs are read: forced, or when auto may pick it (the files
  // are large enough to hold auto_min_points() points).
  const uint64_t min_points = auto_min_points();
  std::optional<GpuStart> start;
  const uint64_t estimate = options.backend != "cgal" ? estimate_input_points(input_paths) : 0;
  spdlog::debug("about {} input points in the files", estimate);
  if (options.backend == "gpu" || (options.backend == "auto" && estimate >= min_points))
    start.emplace(options.device, options.backend == "auto" && options.device.empty(), estimate);

  Loaded l = read_all(options.input, stats);
  std::string reason = "--backend " + options.backend;
  const uint64_t n = point_count(l.in);
  bool want_gpu = options.backend == "gpu";
  if (options.backend == "auto") {
    want_gpu = n >= min_points;
    if (!want_gpu)
      reason = std::to_string(n) + " input points, fewer than " + std::to_string(min_points) +
               ": the CPU is faster than the GPU's start-up";
    else if (!start)
      start.emplace(options.device, options.device.empty(), n);  // a device named with --device is used as it is
  }
  // The GPU is waited for as late as possible, so that its start (~160 ms on the H100 machine) overlaps the
  // CPU's work: reading, the duplicate merge and resolving the constraints. The merge stays on the CPU even
  // when the device is ready: on all 16 cores of the H100 machine it took 31-44 ms for 2.5M points, the GPU's
  // (gpu/dedupe, the same result) ~59 ms with its transfers. Auto falls back to the CPU when the start fails or
  // the device refuses the input; a forced GPU throws.
  prepare_all(l, stats);
  std::optional<gpu::GpuRasteriser> gpu_raster;
  std::optional<gpu::GpuContourer> gpu_contours;
  gpu::GpuCdt* cdt = nullptr;
  stats.backend = "cgal";
  // The GPU path's CPU resolve stage starts now, on other threads, beside the device's start and then the
  // Delaunay build (gpu::GpuCdt::triangulate waits for it where it needs the constraints).
  double resolve_ms = 0;
  std::future<ResolvedInput> resolving;
  if (want_gpu)
    resolving = std::async(std::launch::async, [&] {
      const auto t0 = std::chrono::steady_clock::now();
      ResolvedInput r = resolve_constraints(l.prepared);
      resolve_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      return r;
    });
  CdtResult result = timed(stats, "triangulate", [&] {
    if (want_gpu) {
      timed(stats, "triangulate: gpu start wait", [&] {
        try {
          cdt = &start->cdt();
          if (options.backend == "auto") reason = std::to_string(n) + " input points on a GPU";
        } catch (const gpu::DeviceError& e) {
          if (options.backend == "gpu") throw;
          reason = std::string("no GPU to use (") + e.what() + ")";
        }
      });
    }
    stats.backend = cdt ? "gpu" : "cgal";
    stats.backend_reason = reason;
    spdlog::debug("backend {}: {}", stats.backend, reason);
    if (!cdt) return triangulate_cpu(l.prepared, options.max_tile_points, stats);
    stats.stage_ms.emplace_back("gpu start: context (own thread)", start->context_ms);
    stats.stage_ms.emplace_back("gpu start: pipelines queued (own thread)", start->pipelines_ms);
    stats.stage_ms.emplace_back("gpu start: staging memory (own thread)", start->staging_ms);
    stats.device = start->context().info.name;
    spdlog::debug("device: {} ({} {})", stats.device, start->context().info.driver_name,
                  start->context().info.driver_info);
    // With the GPU backend, grids (and the preview's grid) and contour lines are made on the GPU too, with the
    // CPU's values bit for bit. Their pipelines are asked for now, so they compile while the CDT runs.
    if (!options.grid_out.empty() || !options.preview.empty()) gpu_raster.emplace(start->context(), cdt->primitives());
    if (!options.contours_out.empty()) gpu_contours.emplace(start->context(), cdt->primitives());
    // Called in a DeviceError's handler. Auto: the CPU computes the same triangulation (a device too small for
    // the input, or out of memory); a forced GPU rethrows.
    auto on_cpu_instead = [&](const gpu::DeviceError& e) {
      if (options.backend == "gpu") throw;
      stats.backend = "cgal";
      stats.backend_reason = gpu_refused(e);
      spdlog::warn("{}", stats.backend_reason);
      cdt = nullptr;
      gpu_raster.reset();
      gpu_contours.reset();
      return triangulate_cpu(l.prepared, options.max_tile_points, stats);
    };
    const uint64_t tile = gpu_tile_points(start->context(), l.prepared.vertices.size(), options.max_tile_points);
    if (tile >= 3 && l.prepared.vertices.size() > tile) {
      ResolvedInput in = timed(stats, "triangulate: resolve wait", [&] { return resolving.get(); });
      stats.stage_ms.emplace_back("triangulate: resolve (other threads)", resolve_ms);
      try {
        return triangulate_in_tiles(std::move(in), tile, gpu::gpu_tile_triangulator(*cdt), stats, 2);
      } catch (const gpu::DeviceError& e) {
        return on_cpu_instead(e);
      }
    }
    gpu::GpuCdtStats gs;
    CdtResult r;
    try {
      r = cdt->triangulate(l.prepared, std::move(resolving), &gs);
    } catch (const gpu::DeviceError& e) {
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
  });
  const RegionRules rules = region_rules(l.in, l.parts, l.prepared, options.max_edge);
  const RegionStats rs = timed(stats, "regions", [&] { return apply_regions(result.mesh, l.prepared, rules); });
  if (rs.triangles_outside || rs.triangles_trimmed)
    spdlog::info("dropped {} triangles outside boundaries or inside holes, {} by --max-edge", rs.triangles_outside,
                 rs.triangles_trimmed);
  stats.counts["triangles_outside_regions"] = rs.triangles_outside;
  stats.counts["triangles_trimmed"] = rs.triangles_trimmed;
  stats.counts["vertices_outside_regions"] = rs.vertices_removed;
  if (result.mesh.triangles.empty())
    spdlog::warn(rs.triangles_outside || rs.triangles_trimmed
                     ? "no triangles: boundaries, holes and --max-edge dropped them all"
                     : "no triangles: fewer than 3 distinct points, or all points collinear");
  // Derived outputs are computed before anything is written: a grid that cannot be made writes nothing.
  std::optional<gpu::DeviceTin> tin;  // the final mesh on the device, uploaded once for all of them
  auto device_tin = [&]() -> const gpu::DeviceTin& {
    if (!tin) tin = timed(stats, "tin upload", [&] { return gpu::upload_tin(start->context(), result.mesh); });
    return *tin;
  };
  // A device that cannot hold the work (a mesh or a grid row beyond its buffer range) leaves it to the CPU,
  // whose result is the same.
  auto on_cpu = [&](const gpu::DeviceError& e, const char* what) {
    spdlog::warn("{} on the CPU: {}", what, e.what());
    stats.stage_ms.emplace_back(std::string(what) + ": on the CPU after a device refusal", 0.0);
  };
  auto grid_of = [&](double cell, const char* name) {
    const GridSpec spec = grid_for(result.mesh, cell);
    if (gpu_raster) try {
        Raster r = gpu_raster->rasterise(device_tin(), spec);
        stats.gpu_stage_ms[name] = gpu_raster->gpu_ms;
        return r;
      } catch (const gpu::DeviceError& e) {
        on_cpu(e, name);
      }
    return rasterise(result.mesh, spec);
  };
  std::optional<Raster> grid;
  std::vector<Contour> contours;
  if (!options.grid_out.empty()) grid = timed(stats, "grid", [&] { return grid_of(options.cell, "grid"); });
  if (!options.contours_out.empty())
    contours = timed(stats, "contours", [&] {
      if (gpu_contours) try {
          std::vector<Contour> lines = gpu_contours->lines(device_tin(), result.mesh, options.interval);
          stats.gpu_stage_ms["contours"] = gpu_contours->gpu_ms;
          stats.stage_ms.emplace_back("contours: host sort and chaining", gpu_contours->chain_ms);
          return lines;
        } catch (const gpu::DeviceError& e) {
          on_cpu(e, "contours");
        }
      return contour_lines(result.mesh, options.interval);
    });
  std::optional<Raster> preview;
  if (!options.preview.empty())
    preview = timed(stats, "preview", [&] { return grid_of(preview_cell(result.mesh, 1000), "preview"); });
  // A .prj beside a device, FIFO or /dev/stdout makes no sense (it would be /dev/stdout.prj): the CRS name
  // in the stream is all such an output gets.
  auto crs_for = [&](const std::string& path) {
    Crs c = l.crs;
    if (is_special_output(path)) c.wkt.clear();
    return c;
  };
  timed(stats, "write", [&] {
    if (!options.output.empty()) write_mesh_file(result.mesh, crs_for(options.output), write, options.output);
    if (!options.tiles_out.empty()) {
      // Pieces as large as the run's tiles, else a million points a file.
      const uint64_t piece = options.max_tile_points > 0 ? uint64_t(options.max_tile_points) : 1'000'000;
      const std::vector<MeshPiece> pieces = split_mesh(result.mesh, piece);
      write_tiles_dir(pieces, l.crs, write, options.tiles_out);
      stats.counts["tile_files"] = pieces.size();
    }
    if (grid) write_ascii_grid_file(*grid, crs_for(options.grid_out), options.grid_out);
    if (!options.contours_out.empty())
      write_contours_wkt_file(contours, crs_for(options.contours_out), options.contours_out);
    if (preview) {
      std::vector<uint8_t> rgba = hillshade_rgba(*preview);
      draw_edges(rgba, preview->spec, l.prepared.vertices, l.prepared.constraints);
      write_png_file(options.preview, preview->spec.ncols, preview->spec.nrows, rgba);
    }
  });

  if (grid) stats.counts["grid_cells"] = grid->z.size();
  if (!options.contours_out.empty()) stats.counts["contour_lines"] = contours.size();
  stats.counts["steiner_points"] = result.steiner_points;
  stats.counts["vertices"] = result.mesh.vertices.size();
  stats.counts["triangles"] = result.mesh.triangles.size();
  spdlog::info("{} vertices, {} triangles ({} constraints, {} Steiner points)", result.mesh.vertices.size(),
               result.mesh.triangles.size(), l.prepared.constraints.size(), result.steiner_points);
  if (cdt) stats.stage_ms.emplace_back("triangulate: pipeline waits", gpu::pipeline_wait_ms());
  if (cdt) {
    stats.stage_ms.emplace_back("gpu: memory allocation and release (all threads)", gpu::memory_ms());
    spdlog::debug("gpu memory allocation and release: {:.1f} ms (all threads)", gpu::memory_ms());
  }
  timed(stats, "release", [&] {
    if (start) start->leave_for_exit();
    start.reset();
    l = Loaded{};
    result = CdtResult{};
  });
  write_stats(stats, options.stats_path);
  return 0;
}

int run_verify(const std::string& mesh_path, const InputOptions& options) {
  RunStats stats;
  // A --tiles-out folder: the union of its files, each triangle in exactly one (checked), verified as one mesh.
  Mesh mesh = std::filesystem::is_directory(mesh_path) ? read_tiles_dir(mesh_path) : read_mesh_file(mesh_path);
  Loaded l = load(options, stats);
  const RegionRules rules = region_rules(l.in, l.parts, l.prepared, 0);
  const bool regions = std::count(rules.region_edge.begin(), rules.region_edge.end(), 1) > 0;
  VerifyReport report = regions ? verify_regions(mesh, l.prepared, rules) : verify_mesh(mesh, l.prepared);
  for (const std::string& f : report.failures) spdlog::error("{}: {}", mesh_path, f);
  if (!report.ok()) {
    spdlog::error("{}: NOT the constrained Delaunay triangulation of the inputs", mesh_path);
    return 1;
  }
  spdlog::info("{}: ok ({} vertices, {} triangles, {} constrained edges, {} Steiner vertices)", mesh_path,
               mesh.vertices.size(), mesh.triangles.size(), report.constrained_edges, report.steiner_vertices);
  return 0;
}

}  // namespace cdtgpu
