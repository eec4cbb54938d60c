// cdtgpu command line: parses options and calls cli/run.cpp. Exit codes: 0 ok, 1 verify failed,
// 2 bad input or usage, 3 any other failure (GPU, out of memory, internal).
#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

#include "bench/bench.hpp"
#include "cli/run.hpp"
#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "core/error.hpp"

using namespace cdtgpu;

namespace {

void add_input_options(CLI::App* cmd, InputOptions& in, std::string& crs, std::string& utm_zone,
                       std::string& epsg) {
  cmd->add_option("--z-field", in.read.z_field, "DBF attribute holding z for shapefiles (e.g. ELEV)");
  cmd->add_option("--crs", crs,
                  "auto (lon/lat -> UTM zone of the data's centre, projected input kept), none, a UTM zone such "
                  "as 55S, or EPSG:CODE")
      ->default_val("auto");
  cmd->add_option("--utm-zone", utm_zone, "project lon/lat input to this WGS 84 UTM zone, e.g. 55S");
  cmd->add_option("--epsg", epsg, "project lon/lat input to EPSG 326xx/327xx, 283xx (GDA94 MGA), 78xx (GDA2020 MGA)");
}

CrsRequest crs_from(const std::string& crs, const std::string& utm_zone, const std::string& epsg) {
  int given = (crs != "auto") + !utm_zone.empty() + !epsg.empty();
  if (given > 1) throw UsageError("give only one of --crs, --utm-zone and --epsg");
  if (!utm_zone.empty()) return parse_crs(utm_zone);
  if (!epsg.empty()) return parse_crs("EPSG:" + epsg);
  return parse_crs(crs);
}

// Option checks whose messages say what is allowed in words (CLI11's own print the range's bound as a
// 309-digit number).
CLI::Validator number_check(const char* what, bool (*ok)(double)) {
  return CLI::Validator(
      [what, ok](std::string& text) -> std::string {
        double v = 0;
        const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
        if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v))
          return "'" + text + "' is not a number";
        return ok(v) ? std::string() : "must be " + std::string(what) + ", not " + text;
      },
      what);
}
const CLI::Validator positive = number_check("a number greater than 0", [](double v) { return v > 0; });
const CLI::Validator non_negative = number_check("0 or more", [](double v) { return v >= 0; });

}  // namespace

int main(int argc, char** argv) {
  auto logger = spdlog::stderr_color_mt("cdtgpu");
  logger->set_pattern("cdtgpu: %^%l%$: %v");
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::info);

  CLI::App app{"cdtgpu: constrained Delaunay triangulation (TIN) of GIS contours, DEM points and footprints"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "cdtgpu 0.1.0");
  // Subcommands let -v / -q / --device fall through to here, so they may come anywhere on the line.
  app.fallthrough();
  bool verbose = false, quiet = false;
  std::string device;
  app.add_flag("-v,--verbose", verbose, "log every stage and its time")->configurable(false);
  app.add_flag("-q,--quiet", quiet, "log only warnings and errors");
  app.add_option("--device", device, "Vulkan device: index or part of the name, as `cdtgpu devices` lists");

  TriangulateOptions tri;
  std::string crs = "auto", utm_zone, epsg;
  auto* t = app.add_subcommand("triangulate", "triangulate inputs into a TIN");
  t->add_option("inputs", tri.input.inputs,
                "input files: .shp .wkt .xyz .csv .txt .asc .tif, or - for WKT on stdin; each may end in options "
                ":role=breakline|vertices|boundary|hole and/or z=FIELD|NUMBER|drape|min|mean|max, comma-separated "
                "(e.g. lakes.shp:role=hole, footprints.shp:role=breakline,z=drape)")
      ->required();
  t->add_option("-o,--output", tri.output,
                 "output mesh (.obj .ply .wkt .xml (LandXML) .2dm), or - for stdout (needed unless --tiles-out)");
  t->add_option("--format", tri.format, "obj, ply, wkt, landxml or 2dm (default: from the output's extension)");
  t->add_flag("--ascii", tri.write.ascii, "PLY: ascii instead of binary little-endian");
  t->add_flag("--wkt-multipolygon", tri.write.wkt_multipolygon, "WKT: MULTIPOLYGON Z instead of TIN Z");
  t->add_option("--backend", tri.backend,
                 "auto (default: the GPU for inputs of 100K points or more when a hardware GPU is there, else "
                 "CGAL), gpu (Vulkan compute, any device, lavapipe included) or cgal (the CPU reference)")
      ->default_val("auto")
      ->check(CLI::IsMember({"auto", "gpu", "cgal"}));
  t->add_option("--grid-out", tri.grid_out, "also write the TIN as a DEM grid (.tif: GeoTIFF; else ESRI ASCII .asc), NODATA outside");
  t->add_option("--cell", tri.cell, "grid cell size; cell centres at its multiples")
      ->default_val(1.0)
      ->check(positive);
  t->add_option("--contours-out", tri.contours_out,
                "also write contour lines: WKT LINESTRING Z, one per line (.geojson: GeoJSON)");
  t->add_option("--interval", tri.interval, "contour interval; levels at its multiples")
      ->default_val(10.0)
      ->check(positive);
  t->add_option("--preview", tri.preview, "also write a hillshaded picture of the TIN (PNG, about 1000 px wide)");
  t->add_option("--stats", tri.stats_path, "write counts, CRS and stage times as JSON to this file");
  t->add_option("--max-edge", tri.max_edge,
                 "drop triangles reached from outside across an unconstrained edge longer than this (concave hull)")
      ->check(positive);
  t->add_option("--tiles-out", tri.tiles_out,
                 "also (or only) write the mesh as one file per tile into this folder, with index.geojson: each "
                 "triangle in the file of the tile holding its smallest vertex (format from --format, default PLY; "
                 "tiles of --max-tile-points, default 1M points); `cdtgpu verify DIR` reads it back");
  t->add_option("--max-tile-points", tri.max_tile_points,
                 "triangulate in tiles of at most N input points, merged exactly (the same output); 0: never. "
                 "Default: tiles on every core for the CPU backend at 100K points or more, and for the GPU when "
                 "the input exceeds what the device holds")
      ->check(non_negative);
  add_input_options(t, tri.input, crs, utm_zone, epsg);

  std::string mesh_path;
  InputOptions ver;
  auto* v = app.add_subcommand("verify", "check a mesh is the constrained Delaunay triangulation of the inputs");
  v->add_option("mesh", mesh_path, "mesh written by cdtgpu triangulate, or a --tiles-out folder")->required();
  v->add_option("inputs", ver.inputs, "the inputs it was made from, with the same options")->required();
  add_input_options(v, ver, crs, utm_zone, epsg);

  BenchOptions bench;
  auto* b = app.add_subcommand("bench", "time the paper's workloads with CGAL and the GPU; print the tables");
  add_bench_options(b, bench);

  auto* d = app.add_subcommand("devices", "list the Vulkan devices and say which one would be used");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  if (verbose) spdlog::set_level(spdlog::level::debug);
  if (quiet) spdlog::set_level(spdlog::level::warn);

  try {
    if (*t) {
      tri.device = device;
      tri.input.crs = crs_from(crs, utm_zone, epsg);
      return run_triangulate(tri);
    }
    if (*v) {
      ver.crs = crs_from(crs, utm_zone, epsg);
      return run_verify(mesh_path, ver);
    }
    if (*b) {
      bench.device = device;
      return run_bench(bench);
    }
    if (*d) {
      std::cout << gpu::describe_devices(device);
      return 0;
    }
  } catch (const InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const UsageError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const gpu::DeviceError& e) {  // no usable device, a device limit, device memory, device lost
    spdlog::error("{}", e.what());
    if (*t) spdlog::error("--backend cgal computes the same triangulation on the CPU, without a GPU");
    if (*b) spdlog::error("--cgal-only times CGAL without a GPU");
    return 3;
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory");
    return 3;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 3;
  }
  return 0;
}
