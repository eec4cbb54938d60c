#include "cli/options.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "core/error.hpp"

namespace cdtgpu {
namespace {

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

void add_verify_options(CLI::App* cmd, double& max_edge) {
  cmd->add_option("--max-edge", max_edge, "the --max-edge the mesh was made with (its trimming is checked)")
      ->check(non_negative);
}

void add_input_options(CLI::App* cmd, InputOptions& in, CrsArgs& crs) {
  cmd->add_option("--z-field", in.read.z_field, "DBF attribute holding z for shapefiles (e.g. ELEV)");
  cmd->add_option("--crs", crs.crs,
                  "auto (lon/lat -> UTM zone of the data's centre, projected input kept), none, a UTM zone such "
                  "as 55S, or EPSG:CODE")
      ->default_val("auto");
  cmd->add_option("--utm-zone", crs.utm_zone, "project lon/lat input to this WGS 84 UTM zone, e.g. 55S");
  cmd->add_option("--epsg", crs.epsg,
                  "project lon/lat input to EPSG 326xx/327xx, 283xx (GDA94 MGA), 78xx (GDA2020 MGA)");
}

void add_triangulate_options(CLI::App* t, TriangulateArgs& args) {
  TriangulateOptions& tri = args.tri;
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
  t->add_option("--initial-dt", tri.initial_dt,
                "GPU backend: how the Delaunay triangulation starts: insertion (default: one triangle, then "
                "parallel insertion rounds) or voronoi (the paper's digital Voronoi diagram on a grid, its dual "
                "repaired and flipped Delaunay); the output is the same. voronoi implies --backend gpu")
      ->default_val("insertion")
      ->check(CLI::IsMember({"insertion", "voronoi"}));
  t->add_option("--grid-out", tri.grid_out, "also write the TIN as a DEM grid (.tif: GeoTIFF; else ESRI ASCII .asc), NODATA outside");
  t->add_option("--cell", tri.cell, "grid cell size; cell centres at its multiples")->default_val(1.0)->check(positive);
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
                "the input exceeds what the device holds (then a quarter of the input on one device; on several a "
                "twelfth a device, but at least 2^25 points and a 64th of the input and at most a quarter a "
                "device; never more than a device holds)")
      ->check(non_negative);
  t->add_option("--devices", tri.devices,
                "GPUs for tiled runs: all, or indices 0,2,3 as `cdtgpu devices` lists them; default: all hardware "
                "GPUs when the run is tiled on a host with several, else the one device")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            bool ok = text == "all" || (!text.empty() && text.front() != ',' && text.back() != ',' &&
                                        text.find(",,") == std::string::npos);
            for (char c : text) ok = ok && (text == "all" || (c >= '0' && c <= '9') || c == ',');
            return ok ? std::string() : "must be all or device indices separated by commas (e.g. 0,2), not " + text;
          },
          "all|INDEX,..."));
  add_input_options(t, tri.input, args.crs);
}

CrsRequest crs_from(const CrsArgs& a) {
  int given = (a.crs != "auto") + !a.utm_zone.empty() + !a.epsg.empty();
  if (given > 1) throw UsageError("give only one of --crs, --utm-zone and --epsg");
  if (!a.utm_zone.empty()) return parse_crs(a.utm_zone);
  if (!a.epsg.empty()) return parse_crs("EPSG:" + a.epsg);
  return parse_crs(a.crs);
}

TriangulateOptions triangulate_options(const TriangulateArgs& args) {
  TriangulateOptions o = args.tri;
  o.input.crs = crs_from(args.crs);
  if (o.initial_dt == "voronoi") {  // a stage of the GPU backend only
    if (o.backend == "cgal")
      throw UsageError("--initial-dt voronoi is a GPU method: CGAL builds its own Delaunay triangulation; use "
                       "--backend gpu (or auto)");
    o.backend = "gpu";
  }
  return o;
}

TriangulateOptions parse_job_words(std::vector<std::string> words, const JobDefaults& defaults) {
  if (!words.empty() && words.front() == "triangulate") words.erase(words.begin());
  CLI::App app{"one job of cdtgpu batch", "triangulate"};
  app.set_help_flag();  // --help in a job line is an unknown option, not a help text in the middle of a batch
  TriangulateArgs args;
  bool log_flag = false;
  app.add_flag("-v,--verbose,-q,--quiet", log_flag);
  app.add_option("--device", args.tri.device);
  add_triangulate_options(&app, args);
  std::reverse(words.begin(), words.end());  // CLI11 takes the words last first
  try {
    app.parse(words);
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  if (!defaults.backend.empty() && app.get_option("--backend")->count() == 0) args.tri.backend = defaults.backend;
  if (app.get_option("--device")->count() == 0) args.tri.device = defaults.device;
  return triangulate_options(args);
}

}  // namespace cdtgpu
