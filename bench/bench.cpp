// cdtgpu bench: generate each workload, prepare it, time the fast CGAL CDT (and the GPU backend when given),
// check the triangles against the reference backend, print the table and optionally write every figure as JSON.
#include "bench/bench.hpp"
#include "bench/e2e.hpp"
#include "bench/figures.hpp"
#include "bench/peer.hpp"
#include "bench/grid.hpp"
#include "bench/tiles.hpp"
#include "bench/las.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <numeric>
#include <thread>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>
#include <CGAL/version.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/workloads.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using FastCdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using SortTraits = CGAL::Spatial_sort_traits_adapter_2<K, CGAL::Pointer_property_map<K::Point_2>::type>;
using figures::Clock;
using figures::median;
using figures::ms_since;

std::string fmt_ms(double v) { return figures::fmt(v, 2); }
using json = nlohmann::ordered_json;

constexpr uint64_t kCheckLimit = 200000;  // points; the quick sizes are all below
constexpr double kFraction = 0.5;          // subset fraction of tables 1 and 2
constexpr double kLongFraction = 0.02;     // subset fraction of the long-constraint table

const char* kCgalConfig =
    "CGAL " CGAL_VERSION_STR " Constrained_Delaunay_triangulation_2<Epick, TDS with vertex index, "
    "Exact_predicates_tag>; points spatially sorted (CGAL::spatial_sort) and inserted with a hint, constraints "
    "inserted by vertex handle; time = point insertion + constraint insertion, one thread";

const char* kCgalDtConfig =
    "CGAL " CGAL_VERSION_STR " Delaunay_triangulation_2<Epick, TDS with vertex index>, range insertion (spatial "
    "sort, then insertion with hints); time = construction, one thread";



struct Workload {
  std::string table, name;
  uint64_t points = 0, constraints = 0;  // requested: constraints only for the uniform tables
  double fraction = 0;
  uint32_t grid = 0;  // terrain only
};

uint64_t parse_size(const std::string& s) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    throw UsageError("--sizes: not a number: '" + s + "'");
  }
  std::string suffix = s.substr(used);
  if (suffix == "K" || suffix == "k") v *= 1e3;
  else if (suffix == "M" || suffix == "m") v *= 1e6;
  else if (!suffix.empty()) throw UsageError("--sizes: unknown suffix in '" + s + "' (use K or M)");
  if (!(v >= 3 && v <= 1e9)) throw UsageError("--sizes: '" + s + "' must be between 3 and 1e9 points");
  return static_cast<uint64_t>(std::llround(v));
}

// The tables of the paper, scaled: table 1 keeps the constraint count at half the smallest size (1M..4M points,
// 500K constraints), table 2 uses twice the smallest size with 10%..50% as many constraints (2M points, 200K..1M).
std::vector<Workload> plan(const BenchOptions& o) {
  std::vector<uint64_t> sizes;
  for (const auto& s : o.sizes) sizes.push_back(parse_size(s));
  if (sizes.empty()) sizes = o.quick ? std::vector<uint64_t>{20000, 40000, 60000, 80000}
                                     : std::vector<uint64_t>{1000000, 2000000, 3000000, 4000000};
  const uint64_t smallest = *std::min_element(sizes.begin(), sizes.end());
  // --table 1 alone: the paper's sizes, 1.0 .. 4.0M points in steps of 0.5M.
  const std::vector<uint64_t> paper_table1{1000000, 1500000, 2000000, 2500000, 3000000, 3500000, 4000000};
  const bool all = o.table == "all";
  std::vector<Workload> w;
  const std::vector<uint64_t>& table1 = o.table == "1" && o.sizes.empty() && !o.quick ? paper_table1 : sizes;
  if (all || o.table == "1")
    for (uint64_t n : table1) w.push_back({"1", "uniform+dt-edges", n, smallest / 2, kFraction, 0});
  if (all || o.table == "2")
    for (int k = 1; k <= 5; ++k) w.push_back({"2", "uniform+dt-edges", 2 * smallest, 2 * smallest * k / 10, kFraction, 0});
  if (all || o.table == "long")
    for (uint64_t n : sizes) w.push_back({"long", "uniform+long-dt-edges", n, n / 50, kLongFraction, 0});
  if (o.table == "dt") {  // Delaunay only (issue 4's measure): uniform sizes, then a square grid DEM
    std::vector<uint64_t> dt_sizes = o.sizes.empty() && !o.quick ? std::vector<uint64_t>{1000000, 2000000, 4000000, 8000000}
                                                                 : sizes;
    for (uint64_t n : dt_sizes) w.push_back({"dt", "uniform", n, 0, 0, 0});
    // The grid has 4x the first size's points; left out where that passes the largest size (--sizes 256M
    // would ask for a billion points).
    const uint32_t side = static_cast<uint32_t>(std::llround(2 * std::sqrt(double(dt_sizes.front()))));
    if (uint64_t(side) * side <= *std::max_element(dt_sizes.begin(), dt_sizes.end()))
      w.push_back({"dt", "grid", uint64_t(side) * side, 0, 0, side});
  }
  if (all || o.table == "terrain")
    for (uint64_t n : sizes)
      w.push_back({"terrain", "dem+contours", n, 0, 0, static_cast<uint32_t>(std::llround(std::sqrt(double(n))))});
  if (w.empty()) throw UsageError("--table must be 1, 2, long, terrain, dt or all, got '" + o.table + "'");
  return w;
}

// A grid DEM of side x side nodes 10 m apart: every cell's four corners are co-circular.
InputSet grid_points(uint32_t side) {
  InputSet in;
  in.sources = {"grid(" + std::to_string(side) + "x" + std::to_string(side) + ")"};
  in.points.reserve(uint64_t(side) * side);
  for (uint32_t i = 0; i < side; ++i)
    for (uint32_t j = 0; j < side; ++j) in.points.push_back({500000 + 10.0 * i, 6000000 + 10.0 * j, 0});
  return in;
}

InputSet generate(const Workload& w, uint64_t seed) {
  if (w.table == "dt") return w.grid ? grid_points(w.grid) : uniform_points(w.points, seed);
  if (w.grid) {
    TerrainOptions t;
    t.grid = w.grid;
    t.seed = seed;
    return terrain_workload(t);
  }
  InputSet in = uniform_points(w.points, seed);
  add_dt_edge_constraints(in, w.constraints, w.fraction, seed);
  return in;
}

// Mean constraint length in units of the mean point spacing sqrt(bounding-box area / vertices).
double mean_length_in_spacings(const PreparedInput& p) {
  if (p.constraints.empty() || p.vertices.empty()) return 0;
  double x0 = p.vertices.front().x, x1 = p.vertices.back().x, y0 = p.vertices[0].y, y1 = y0;
  for (const Point3& v : p.vertices) y0 = std::min(y0, v.y), y1 = std::max(y1, v.y);
  double spacing = std::sqrt((x1 - x0) * (y1 - y0) / double(p.vertices.size()));
  double sum = 0;
  for (const Edge& e : p.constraints) {
    const Point3 &a = p.vertices[e[0]], &b = p.vertices[e[1]];
    sum += std::hypot(b.x - a.x, b.y - a.y);
  }
  return spacing > 0 ? sum / double(p.constraints.size()) / spacing : 0;
}

struct Timings {
  std::vector<double> total, device;
  std::vector<std::pair<std::string, std::vector<double>>> wall;  // GPU: host clock per pipeline stage
  uint32_t rounds = 0;
  uint64_t peak_device_bytes = 0;
  uint32_t host_fallback = 0;
  std::vector<std::pair<std::string, std::vector<double>>> stages;  // in run order
  Mesh mesh;                                                        // of the last run, canonical

  json to_json() const {
    json j;
    j["median_ms"] = median(total);
    j["runs_ms"] = total;
    if (!device.empty()) {
      j["device_median_ms"] = median(device);
      j["device_runs_ms"] = device;
      j["rounds"] = rounds;
      j["peak_device_bytes"] = peak_device_bytes;
      j["host_fallback_constraints"] = host_fallback;
    }
    json sm = json::object(), sr = json::object();
    for (const auto& [name, v] : stages) {
      sm[name] = median(v);
      sr[name] = v;
    }
    j["stage_median_ms"] = sm;
    j["stage_runs_ms"] = sr;
    if (!wall.empty()) {
      json w = json::object();
      for (const auto& [name, v] : wall) w[name] = median(v);
      j["wall_stage_median_ms"] = w;
    }
    return j;
  }
};

Timings time_backend(const BenchBackend& backend, const PreparedInput& p, int runs) {
  Timings t;
  backend(p);  // warm-up: page faults, allocator, caches
  for (int r = 0; r < runs; ++r) {
    BackendRun run = backend(p);
    t.total.push_back(run.total_ms);
    if (run.device_ms > 0) t.device.push_back(run.device_ms);
    t.rounds = run.rounds;
    t.peak_device_bytes = std::max(t.peak_device_bytes, run.peak_device_bytes);
    t.host_fallback = std::max(t.host_fallback, run.host_fallback);
    for (const auto& [name, ms] : run.stage_ms) {
      auto it = std::find_if(t.stages.begin(), t.stages.end(), [&](const auto& s) { return s.first == name; });
      if (it == t.stages.end()) it = t.stages.insert(t.stages.end(), {name, {}});
      it->second.push_back(ms);
    }
    for (const auto& [name, ms] : run.wall_ms) {
      auto it = std::find_if(t.wall.begin(), t.wall.end(), [&](const auto& s) { return s.first == name; });
      if (it == t.wall.end()) it = t.wall.insert(t.wall.end(), {name, {}});
      it->second.push_back(ms);
    }
    if (r + 1 == runs) t.mesh = std::move(run.mesh);
  }
  canonicalize(t.mesh);
  return t;
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      auto c = line.find(':');
      if (c != std::string::npos) return line.substr(line.find_first_not_of(" \t", c + 1));
    }
  return "unknown";
}

std::string utc_now() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}


// First differing triangle, or empty when the meshes are equal.
std::string mesh_difference(const Mesh& a, const Mesh& b) {
  if (a.vertices.size() != b.vertices.size())
    return std::to_string(a.vertices.size()) + " vs " + std::to_string(b.vertices.size()) + " vertices";
  if (a.vertices != b.vertices) return "vertex coordinates differ";
  if (a.triangles.size() != b.triangles.size())
    return std::to_string(a.triangles.size()) + " vs " + std::to_string(b.triangles.size()) + " triangles";
  for (size_t i = 0; i < a.triangles.size(); ++i)
    if (a.triangles[i] != b.triangles[i]) {
      const auto &s = a.triangles[i], &t = b.triangles[i];
      return "triangle " + std::to_string(i) + ": (" + std::to_string(s[0]) + "," + std::to_string(s[1]) + "," +
             std::to_string(s[2]) + ") vs (" + std::to_string(t[0]) + "," + std::to_string(t[1]) + "," +
             std::to_string(t[2]) + ")";
    }
  return {};
}

}  // namespace

BackendRun run_cgal_fast(const PreparedInput& p) {
  BackendRun r;
  const size_t n = p.vertices.size();
  auto t0 = Clock::now();
  std::vector<K::Point_2> pts;
  pts.reserve(n);
  for (const Point3& v : p.vertices) pts.emplace_back(v.x, v.y);
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  CGAL::spatial_sort(order.begin(), order.end(), SortTraits(CGAL::make_property_map(pts)));
  FastCdt cdt;
  std::vector<FastCdt::Vertex_handle> vh(n);
  FastCdt::Face_handle hint;
  for (std::size_t i : order) {
    FastCdt::Vertex_handle v = cdt.insert(pts[i], hint);
    v->info() = static_cast<uint32_t>(i);
    vh[i] = v;
    hint = v->face();
  }
  double points_ms = ms_since(t0);
  auto t1 = Clock::now();
  for (const Edge& e : p.constraints) cdt.insert_constraint(vh[e[0]], vh[e[1]]);
  double constraints_ms = ms_since(t1);

  auto t2 = Clock::now();
  r.mesh.vertices = p.vertices;
  r.mesh.triangles.reserve(cdt.number_of_faces());
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
    r.mesh.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  double extract_ms = ms_since(t2);
  r.stage_ms = {{"points", points_ms}, {"constraints", constraints_ms}, {"extract", extract_ms}};
  r.total_ms = points_ms + constraints_ms;
  return r;
}

BackendRun run_cgal_delaunay(const PreparedInput& p) {
  using Dt = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<Vb>>;
  BackendRun r;
  auto t0 = Clock::now();
  std::vector<std::pair<K::Point_2, uint32_t>> pts;
  pts.reserve(p.vertices.size());
  for (size_t i = 0; i < p.vertices.size(); ++i) pts.push_back({{p.vertices[i].x, p.vertices[i].y}, uint32_t(i)});
  Dt dt(pts.begin(), pts.end());  // range insertion: spatial sort, then insertion with hints
  r.total_ms = ms_since(t0);
  r.stage_ms = {{"points", r.total_ms}};
  r.mesh.vertices = p.vertices;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
    r.mesh.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  return r;
}

uint64_t parse_bench_size(const std::string& s) { return parse_size(s); }
std::string bench_cpu_model() { return cpu_model(); }
std::string bench_utc_now() { return utc_now(); }

void add_bench_options(CLI::App* cmd, BenchOptions& o) {
  cmd->add_option("--table", o.table,
                  "1 (1M..4M points, 500K constraints), 2 (2M points, 200K..1M constraints), long (long "
                  "constraints), terrain (DEM grid + contours), all (these four), dt (Delaunay only: 1M..8M "
                  "uniform points and a grid, CGAL's Delaunay_triangulation_2), e2e (`cdtgpu triangulate` "
                  "as a child process, files in, PLY out: 20K..4M points + a quarter as many contour segments), "
                  "grid (a terrain TIN's DEM grid and contours, CPU against GPU, and the whole process with "
                  "--grid-out and --contours-out), or peer (GPU stages beside gDel2D's on the same vertices and "
                  "segments, see --peer and --rows), or tiles (the tiled CDT against the single run, CPU and GPU, "
                  "2M and 16M points + a quarter as many segments, in process), or las (LAS files read in process: "
                  "10M and 50M points, formats 1 and 6)")
      ->default_val("all")
      ->check(CLI::IsMember({"1", "2", "long", "terrain", "dt", "all", "e2e", "grid", "peer", "tiles", "las"}));
  cmd->add_flag("--quick", o.quick, "small sizes (20K..80K points; e2e: 20K and 200K) that finish in about a minute on 2 cores");
  cmd->add_option("--tile-points", o.tile_points,
                  "tiles: tiles of at most this many points (default: the CPU's auto size; the GPU: a quarter of the "
                  "input, or what the device holds)");
  cmd->add_flag("--points-only", o.points_only, "tiles: uniform points without constraint segments");
  cmd->add_option("--tiles-in-flight", o.tiles_in_flight, "tiles: GPU tiles worked on at once, per device (cdtgpu triangulate: 2)")
      ->check(CLI::Range(1, 16));
  cmd->add_option("--tile-ramps", o.tile_ramps,
                  "tiles: a GPU tiled row for each of these ramps, the first and the last slab cut into this many "
                  "(0 or 1: none; without the option, cdtgpu triangulate's: 2 for tiles of 100M points or more on a GPU)")
      ->delimiter(',');
  cmd->add_flag("--in-runs", o.in_runs,
                "tiles: GPU tiled rows leave the canonical order in the tiles' runs, as cdtgpu triangulate does for "
                "a mesh it only writes (gathered into one array untimed, for the comparison)");
  cmd->add_option("--devices", o.devices,
                  "tiles: also GPU tiled rows on several devices, 2, 4, ... up to all of these (all, or indices "
                  "0,1,... as `cdtgpu devices` lists them)");
  cmd->add_option("--sizes", o.sizes, "point counts replacing the table's, e.g. 50K,100K or 1.5M")->delimiter(',');
  cmd->add_option("--runs", o.runs, "timed runs per backend and workload; the median is reported")
      ->default_val(5)
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--cgal-runs", o.cgal_runs, "timed CGAL runs (default: --runs); CGAL takes seconds per run")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--json", o.json_path, "write every figure (each run's times too) and machine info here");
  cmd->add_option("--seed", o.seed, "seed of the workload generators")->default_val(1);
  cmd->add_flag("--check", o.check, "compare with the reference CGAL backend at every size (default: up to 200K)");
  cmd->add_flag("!--cgal-only", o.gpu, "time CGAL only (no Vulkan device needed)");
  cmd->add_flag("--ablation", o.ablation,
                "the paper's Table 3: the first --sizes value (default 2M points, 40K with --quick) with a tenth, a "
                "quarter and half as many constraints; the full method and each part switched off");
  cmd->add_option("--backends", o.backends,
                  "e2e: the child's --backend values to time, and batch: one `cdtgpu batch` of --batch-jobs jobs "
                  "(default auto,gpu,cgal,batch)")
      ->delimiter(',');
  cmd->add_option("--batch-jobs", o.batch_jobs, "e2e: jobs in the batch row, each the row's whole run (default 20)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--formats", o.formats,
                  "e2e: input formats (default text,shp): text (.xyz + .wkt), shp, las (LAS 1.4 points + .wkt), "
                  "and a DEM grid of about as many cells + the .wkt as asc (ESRI ASCII) or tif (GeoTIFF)")
      ->delimiter(',')
      ->check(CLI::IsMember({"text", "shp", "las", "asc", "tif"}));
  cmd->add_option("--binary", o.binary, "e2e: the cdtgpu executable to time (default: this one)");
  cmd->add_flag("!--no-first-run", o.first_run,
                "e2e: skip the run with empty shader and pipeline caches (minutes on lavapipe, which compiles every "
                "pipeline then)");
  cmd->add_option("--peer", o.peer, "peer: gDel2D's executable, run on each row's input in its binary format");
  cmd->add_option("--rows", o.rows, "peer: POINTS+SEGMENTS rows (default 2M,8M,2M+500K,2M+1M,4M+1M)")->delimiter(',');
  cmd->add_option("--cgal-max", o.cgal_max_points,
                  "no CGAL run (so no comparison) above this many points, where CGAL takes minutes (default 10M)")
      ->transform([](std::string s) {
        if (s == "0") return s;  // no CGAL run at all
        try {
          return std::to_string(parse_bench_size(s));
        } catch (const UsageError& e) {  // a message and exit 2, not an uncaught exception
          std::string m = e.what();
          if (m.rfind("--sizes: ", 0) == 0) m = m.substr(9);
          throw CLI::ValidationError(m);
        }
      });
  cmd->add_option("--keep", o.keep_dir, "e2e: write inputs, outputs, stats and logs into this folder and keep them");
  cmd->add_option("--grid-cells", o.grid_cells,
                  "grid: cells on the grid's long side (default 10000, a 10000 x 10000 grid; --quick: 1000)");
}

namespace {

// The GPU backend as the bench times it: total_ms is the host wall clock of the whole backend (uploads, every
// submit and readback, the wait for the CPU resolve that runs beside the Delaunay build, download in canonical
// order); stage_ms splits it into the resolve wait, the device time of each GPU stage, the download and the rest
// (host work between submits, waiting).
BenchBackend gpu_backend(const gpu::GpuCdt& cdt) {
  return [&cdt](const PreparedInput& p) {
    gpu::GpuCdtStats s;
    BackendRun r;
    CdtResult res = cdt.triangulate(p, &s);
    r.mesh = std::move(res.mesh);
    double accounted = 0;
    auto add = [&](const std::string& name, double ms) {  // stages repeat when the Delaunay build ran twice
      auto it = std::find_if(r.stage_ms.begin(), r.stage_ms.end(), [&](const auto& x) { return x.first == name; });
      if (it == r.stage_ms.end()) r.stage_ms.emplace_back(name, ms);
      else it->second += ms;
    };
    for (const auto& [name, ms] : s.wall_ms)
      if (name == std::string("resolve wait") || name == std::string("upload") || name == std::string("download")) {
        add(name + " (host)", ms);
        accounted += ms;
      }
    for (const auto& [name, ms] : s.gpu_ms) add(name, ms);
    r.stage_ms.emplace_back("host overhead", std::max(0.0, s.wall_total_ms - accounted - s.gpu_total_ms));
    r.total_ms = s.wall_total_ms;
    r.device_ms = s.gpu_total_ms;
    r.wall_ms = s.wall_ms;
    r.rounds = s.delaunay.rounds + s.constraints.flip_rounds + s.constraints.legalise_rounds;
    r.peak_device_bytes = s.peak_device_bytes;
    r.host_fallback = s.constraints.fallback_constraints;
    return r;
  };
}

// Times the GPU backend on a context of its own, created after CGAL's runs, as each `cdtgpu triangulate` call
// creates one. Why: the H100's driver raises the SM clock to 1980 MHz when a context is created and drops it to
// 345 MHz after ~3 s without sustained load (CGAL's seconds are such a gap); our bursts of work do not raise it
// again, so one context shared by every workload timed its later rows ~3.5x slow (nvidia-smi, docs/performance.md).
// `merge`, when given: also prepare `in` with the GPU's duplicate merging (as `cdtgpu triangulate` does), once
// after a warm-up, into merge->ms, and check it equals `p` (the CPU's) into merge->difference.
struct GpuMerge {
  const InputSet* in = nullptr;
  double ms = 0;
  std::string difference;
};

std::string prepared_difference(const PreparedInput& a, const PreparedInput& b) {
  if (a.vertices.size() != b.vertices.size())
    return std::to_string(a.vertices.size()) + " vs " + std::to_string(b.vertices.size()) + " vertices";
  for (size_t v = 0; v < a.vertices.size(); ++v)
    if (std::memcmp(&a.vertices[v], &b.vertices[v], sizeof(Point3)) != 0) return "vertex " + std::to_string(v);
  if (a.constraints != b.constraints || a.constraint_line != b.constraint_line) return "constraints";
  if (a.merged_duplicates != b.merged_duplicates || a.z_conflicts != b.z_conflicts ||
      a.max_z_conflict != b.max_z_conflict || a.duplicate_segments != b.duplicate_segments)
    return "counts";
  return "";
}

using Start = gpu::DelaunayBuilder::Start;

Timings time_gpu(const gpu::ContextOptions& co, const gpu::ConstraintOptions& options, const PreparedInput& p,
                 int runs, GpuMerge* merge = nullptr, Start start = Start::insertion) {
  gpu::Context ctx = gpu::create_context(co);
  gpu::GpuCdt cdt(ctx);
  cdt.constraint_options = options;
  cdt.delaunay().initial_dt = start;
  Timings t = time_backend(gpu_backend(cdt), p, runs);
  if (merge) {
    prepare(*merge->in, cdt.merger());  // warm-up
    const auto t0 = Clock::now();
    const PreparedInput q = prepare(*merge->in, cdt.merger());
    merge->ms = ms_since(t0);
    merge->difference = prepared_difference(p, q);
  }
  return t;
}

double stage_median(const Timings& t, const std::string& name) {
  for (const auto& [k, runs] : t.stages)
    if (k == name) return median(runs);
  return 0.0;
}

// The Voronoi first stage's steps (issue 30), medians: GPU discretise, flood, dual; host checks and repair
// (downloads and upload included); GPU flips to Delaunay; and the insertion rounds after it.
std::string voronoi_stages(const Timings& t) {
  char line[256];
  std::snprintf(line, sizeof line,
                "discretise %s, flood %s, dual %s, repair (host) %s, flips %s; then rounds: relocate %s, insert %s, "
                "flip %s",
                fmt_ms(stage_median(t, "dt vd discretise")).c_str(), fmt_ms(stage_median(t, "dt vd flood")).c_str(),
                fmt_ms(stage_median(t, "dt vd dual")).c_str(),
                fmt_ms(stage_median(t, "dt vd repair (host)")).c_str(),
                fmt_ms(stage_median(t, "dt vd flips")).c_str(), fmt_ms(stage_median(t, "dt relocate")).c_str(),
                fmt_ms(stage_median(t, "dt insert")).c_str(), fmt_ms(stage_median(t, "dt flip")).c_str());
  return line;
}

std::string bytes_per_point(const Timings& t, const PreparedInput& p) {
  if (!t.peak_device_bytes || p.vertices.empty()) return "-";
  return std::to_string(t.peak_device_bytes / p.vertices.size());
}

// The paper's Table 3: 2M points (the first --sizes value) with a tenth, a quarter and half as many constraints,
// each workload timed with the full method and with each part switched off in turn.
int run_ablation(const BenchOptions& o, const gpu::ContextOptions& co, const std::string& device) {
  const uint64_t n = o.sizes.empty() ? (o.quick ? 40000 : 2000000) : parse_size(o.sizes.front());
  using Opt = gpu::ConstraintOptions;
  struct Variant {
    std::string name;
    Opt options;
    Start start = Start::insertion;
  };
  std::vector<Variant> variants(6);
  variants[0].name = "full method (with our cavity insertion)";
  variants[1].name = "no prefix-sum layout (fixed slots per constraint)";
  variants[1].options.layout = Opt::Layout::FixedSlots;
  variants[2].name = "no adaptive flipping (one flip per constraint)";
  variants[2].options.flipping = Opt::Flipping::OnePerConstraint;
  variants[3].name = "no influence-domain index (slot claims alone)";
  variants[3].options.domain_index = false;
  variants[4].name = "the paper's method: flips only, no cavity insertion";
  variants[4].options.cavities = false;
  variants[5].name = "Voronoi first stage (--initial-dt voronoi)";
  variants[5].start = Start::voronoi;

  std::printf("ablation (the paper's Table 3): %llu points; 'constraints ms' = device time of crossing detection + "
              "prefix-sum layout + flip rounds; 'host' = constraints the host safety net inserted\n",
              static_cast<unsigned long long>(n));
  json workloads = json::array();
  std::vector<std::vector<double>> device_ms(variants.size());  // [variant][workload], for the summary
  std::vector<uint64_t> counts;
  int failures = 0;
  for (const uint64_t m : {n / 10, n / 4, n / 2}) {
    Workload w{"ablation", "uniform+dt-edges", n, m, kFraction, 0};
    InputSet in = generate(w, o.seed);
    PreparedInput p = prepare(in);
    Timings cgal = time_backend(run_cgal_fast, p, o.cgal_runs > 0 ? o.cgal_runs : o.runs);
    counts.push_back(p.constraints.size());
    std::printf("\n%zu vertices, %zu constraints; CGAL %s ms\n", p.vertices.size(), p.constraints.size(),
                fmt_ms(median(cgal.total)).c_str());
    std::printf("%-50s %10s %10s %15s %8s %6s %5s %s\n", "variant", "GPU ms", "wall ms", "constraints ms",
                "rounds", "B/pt", "host", "check");
    json rows = json::array();
    for (size_t vi = 0; vi < variants.size(); ++vi) {
      const Variant& v = variants[vi];
      Timings t = time_gpu(co, v.options, p, o.runs, nullptr, v.start);
      std::string diff = mesh_difference(t.mesh, cgal.mesh);
      failures += !diff.empty();
      if (!diff.empty()) spdlog::error("ablation '{}' differs from CGAL: {}", v.name, diff);
      auto stage = [&](const char* name) {
        for (const auto& [k, runs] : t.stages)
          if (k == name) return median(runs);
        return 0.0;
      };
      const double insert_ms =
          stage("cdt crossing detection") + stage("cdt prefix-sum layout") + stage("cdt flipping");
      device_ms[vi].push_back(median(t.device));
      std::printf("%-50s %10s %10s %15s %8u %6s %5u %s\n", v.name.c_str(), fmt_ms(median(t.device)).c_str(),
                  fmt_ms(median(t.total)).c_str(), fmt_ms(insert_ms).c_str(), t.rounds,
                  bytes_per_point(t, p).c_str(), t.host_fallback, diff.empty() ? "ok" : "FAIL");
      if (v.start == Start::voronoi) std::printf("    Delaunay stages: %s\n", voronoi_stages(t).c_str());
      std::fflush(stdout);
      json row = t.to_json();
      row["variant"] = v.name;
      row["constraint_insertion_ms"] = insert_ms;
      row["cgal_equal"] = diff.empty();
      rows.push_back(row);
    }
    workloads.push_back({{"vertices", p.vertices.size()},
                         {"constraints", p.constraints.size()},
                         {"cgal", cgal.to_json()},
                         {"variants", rows}});
  }
  // The shape of the paper's Table 3: each variant's GPU time against the full method's, per constraint count.
  std::printf("\n%-50s", "GPU ms (vs full method)");
  for (uint64_t c : counts) std::printf(" %18s", (std::to_string(c) + " constraints").c_str());
  std::printf("\n");
  for (size_t vi = 0; vi < variants.size(); ++vi) {
    std::printf("%-50s", variants[vi].name.c_str());
    for (size_t k = 0; k < counts.size(); ++k)
      std::printf(" %10s (%+4.0f%%)", fmt_ms(device_ms[vi][k]).c_str(),
                  100.0 * (device_ms[vi][k] / device_ms[0][k] - 1.0));
    std::printf("\n");
  }
  if (!o.json_path.empty()) {
    json j;
    j["tool"] = "cdtgpu bench --ablation";
    j["date"] = utc_now();
    j["device"] = device;
    j["points"] = n;
    j["workloads"] = workloads;
    write_file_atomically(o.json_path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
  }
  return failures ? 1 : 0;
}

// Runs the GPU backend once on a small workload with constraints, so that the driver compiles every pipeline
// now. Why: on a fresh machine the first context's pipeline compiles take seconds, longer than the ~3 s SM clock
// boost of a new context, and the first row was then timed at 345 MHz (H100: 1M points 25 ms instead of 7).
void warm_pipelines(const gpu::Context& ctx) {
  InputSet in = uniform_points(20000, 1);
  add_dt_edge_constraints(in, 2000, kFraction, 1);
  gpu::GpuCdt cdt(ctx);
  gpu_backend(cdt)(prepare(in));
}

}  // namespace

int run_bench(const BenchOptions& o) {
  if (o.table == "e2e") return run_e2e(o);  // the child processes open their own devices
  if (o.table == "peer") return run_peer(o);
  if (o.table == "grid") return run_grid(o);
  if (o.table == "tiles") return run_tiles(o);
  if (o.table == "las") return run_las(o);
  gpu::ContextOptions co;
  co.device = o.device;
  std::string device = "none (--cgal-only)", device_name;
  const bool gpu = o.gpu || o.ablation;
  if (gpu) {  // fails early on a missing device; each workload gets a context of its own (time_gpu)
    gpu::Context ctx = gpu::create_context(co);
    device_name = ctx.info.name;
    device = ctx.info.name + ", driver " + ctx.info.driver_name + " " + ctx.info.driver_info;
    warm_pipelines(ctx);
  }
  if (o.ablation) return run_ablation(o, co, device);

  const std::vector<Workload> work = plan(o);
  const std::string cpu = cpu_model(), date = utc_now();
  const unsigned threads = std::thread::hardware_concurrency();
  std::printf("cdtgpu bench, %s\n", date.c_str());
  std::printf("CPU: %s, %u hardware threads\n", cpu.c_str(), threads);
  std::printf("GPU: %s\n", device.c_str());
  std::printf("CGAL column: %s\n", o.table == "dt" ? kCgalDtConfig : kCgalConfig);
  std::printf("GPU columns: 'GPU ms' = device timestamps of the GPU stages; 'wall ms' = the whole GPU backend on the "
              "host clock (CPU constraint resolution, submits, readbacks, download in canonical order); speedup = "
              "CGAL / wall\n");
  std::printf("median of %d runs (CGAL: %d) after 1 warm-up; the GPU backend gets a fresh Vulkan context per "
              "workload, as each `cdtgpu triangulate` run does; seed %llu\n\n",
              o.runs, o.cgal_runs > 0 ? o.cgal_runs : o.runs, static_cast<unsigned long long>(o.seed));
  std::printf("%-8s %9s %9s %11s %9s %9s %9s %8s %6s %6s %9s %5s %s\n", "table", "points", "vertices",
              "constraints", "CGAL ms", "GPU ms", "wall ms", "speedup", "rounds", "B/pt", "triangles", "len", "check");
  std::fflush(stdout);

  json rows = json::array();
  int failures = 0;
  for (const Workload& w : work) {
    auto tg = Clock::now();
    InputSet in = generate(w, o.seed);
    double generate_ms = ms_since(tg);
    auto tp = Clock::now();
    PreparedInput p = prepare(in);
    double prepare_ms = ms_since(tp);

    const int cgal_runs = o.cgal_runs > 0 ? o.cgal_runs : o.runs;
    const bool with_cgal = p.vertices.size() <= o.cgal_max_points;
    Timings cgal;
    if (with_cgal) cgal = time_backend(w.table == "dt" ? run_cgal_delaunay : run_cgal_fast, p, cgal_runs);
    Timings g;
    GpuMerge merge;
    merge.in = &in;
    if (gpu) g = time_gpu(co, {}, p, o.runs, &merge);
    // Table 1 also times the Voronoi first stage (issue 30), which must give the same mesh.
    const bool voronoi = gpu && w.table == "1";
    Timings gv;
    if (voronoi) gv = time_gpu(co, {}, p, o.runs, nullptr, Start::voronoi);

    json check = json::object();
    std::string status = "-";
    if (with_cgal && (o.check || in.points.size() <= kCheckLimit)) {
      auto tr = Clock::now();
      CdtResult ref = triangulate_cgal(p);
      check["reference_ms"] = ms_since(tr);
      check["steiner_points"] = ref.steiner_points;
      std::string diff = mesh_difference(cgal.mesh, ref.mesh);
      if (ref.steiner_points) diff = std::to_string(ref.steiner_points) + " Steiner points: constraints cross";
      check["cgal_equal"] = diff.empty();
      if (!diff.empty()) {
        spdlog::error("{} {} points: fast CGAL differs from the reference: {}", w.table, w.points, diff);
        check["cgal_difference"] = diff;
      }
      status = diff.empty() ? "ok" : "FAIL";
      failures += !diff.empty();
    }
    if (gpu && with_cgal) {
      // The GPU result must equal CGAL's at every size where CGAL runs, checked or not.
      std::string diff = mesh_difference(g.mesh, cgal.mesh);
      check["gpu_equal"] = diff.empty();
      if (!diff.empty()) {
        spdlog::error("{} {} points: the GPU backend differs from CGAL: {}", w.table, w.points, diff);
        check["gpu_difference"] = diff;
        status = "FAIL";
        ++failures;
      } else if (status == "-") {
        status = "gpu=cgal";
      }
      const std::string vdiff = voronoi ? mesh_difference(gv.mesh, cgal.mesh) : "";
      if (voronoi) check["gpu_voronoi_equal"] = vdiff.empty();
      if (!vdiff.empty()) {
        spdlog::error("{} {} points: the GPU backend with the Voronoi start differs from CGAL: {}", w.table, w.points,
                      vdiff);
        status = "FAIL";
        ++failures;
      }
      check["gpu_prepare_equal"] = merge.difference.empty();
      if (!merge.difference.empty()) {
        spdlog::error("{} {} points: prepare with the GPU's merging differs: {}", w.table, w.points, merge.difference);
        status = "FAIL";
        ++failures;
      }
    }

    const double cgal_ms = with_cgal ? median(cgal.total) : std::nan("");
    const double wall_ms = gpu ? median(g.total) : 0;
    const double dev_ms = gpu ? median(g.device) : 0;
    const double len = mean_length_in_spacings(p);
    std::printf("%-8s %9zu %9zu %11zu %9s %9s %9s %8s %6s %6s %9zu %5.2f %s\n", w.table.c_str(), in.points.size(),
                p.vertices.size(), p.constraints.size(), with_cgal ? fmt_ms(cgal_ms).c_str() : "-",
                gpu ? fmt_ms(dev_ms).c_str() : "-", gpu ? fmt_ms(wall_ms).c_str() : "-",
                gpu && with_cgal ? fmt_ms(cgal_ms / wall_ms).c_str() : "-",
                gpu ? std::to_string(g.rounds).c_str() : "-", gpu ? bytes_per_point(g, p).c_str() : "-",
                (with_cgal ? cgal : g).mesh.triangles.size(), len, status.c_str());
    if (voronoi)
      std::printf("%-8s %9s %9s %11s %9s %9s %9s %8s %6u %6s   Voronoi start: %s\n", "1 vd", "", "", "", "",
                  fmt_ms(median(gv.device)).c_str(), fmt_ms(median(gv.total)).c_str(),
                  with_cgal ? fmt_ms(cgal_ms / median(gv.total)).c_str() : "-", gv.rounds,
                  bytes_per_point(gv, p).c_str(), voronoi_stages(gv).c_str());
    std::fflush(stdout);

    json row;
    row["table"] = w.table;
    row["workload"] = w.name;
    row["sources"] = in.sources;
    row["points"] = in.points.size();
    row["input_points"] = p.input_points;
    row["vertices"] = p.vertices.size();
    row["constraints"] = p.constraints.size();
    if (w.fraction > 0) row["subset_fraction"] = w.fraction;
    if (w.grid) row["grid"] = w.grid;
    row["mean_constraint_length_spacings"] = len;
    row["triangles"] = (with_cgal ? cgal : g).mesh.triangles.size();
    row["generate_ms"] = generate_ms;
    row["prepare_ms"] = prepare_ms;
    if (gpu) row["prepare_gpu_merge_ms"] = merge.ms;
    row["cgal"] = with_cgal ? cgal.to_json() : json();
    row["gpu"] = gpu ? g.to_json() : json();
    if (voronoi) row["gpu_voronoi"] = gv.to_json();
    row["speedup"] = gpu && with_cgal ? json(cgal_ms / wall_ms) : json();
    row["speedup_device"] = gpu && with_cgal ? json(cgal_ms / dev_ms) : json();
    row["check"] = check;
    rows.push_back(row);
  }

  if (!o.json_path.empty()) {
    json j;
    j["tool"] = "cdtgpu bench";
    j["date"] = date;
    j["machine"] = {{"cpu", cpu}, {"hardware_threads", threads}, {"gpu", device}};
    j["cgal_config"] = o.table == "dt" ? kCgalDtConfig : kCgalConfig;
    j["gpu_backend"] = gpu ? json("GPU (" + device_name + ")") : json();
    j["runs"] = o.runs;
    j["cgal_runs"] = o.cgal_runs > 0 ? o.cgal_runs : o.runs;
    j["warmup_runs"] = 1;
    j["gpu_context"] = "one per workload, created after CGAL's runs";
    j["seed"] = o.seed;
    j["quick"] = o.quick;
    j["rows"] = rows;
    write_file_atomically(o.json_path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
  }
  if (failures) spdlog::error("{} workload(s) failed the check", failures);
  return failures ? 1 : 0;
}

}  // namespace cdtgpu
