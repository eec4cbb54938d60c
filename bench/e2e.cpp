// The end-to-end table: writes each row's inputs, runs `cdtgpu triangulate` on them as a child process per
// format and backend (first run with empty caches, a warm-up, then --runs timed runs), reads each run's stats
// JSON, compares the PLY outputs byte for byte, prints one line per row x format x backend and writes JSON.
#include "bench/figures.hpp"
#include "bench/e2e.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "bench/child.hpp"
#include "bench/e2e_workload.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;
using figures::Clock;
using figures::median;
using figures::ms_since;
using figures::fmt;
using json = nlohmann::ordered_json;




// The last line of a child's log that says something, for the table's failure note (CLI11's closing advice
// to run --help says nothing: the line before it names the option).
std::string last_line(const std::string& log) {
  std::istringstream s(log);
  std::string line, last;
  while (std::getline(s, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos && line.rfind("Run with --help", 0) != 0)
      last = line;
  return last;
}

bool same_bytes(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  if (fs::file_size(a, ea) != fs::file_size(b, eb) || ea || eb) return false;
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  std::vector<char> ba(1 << 20), bb(1 << 20);
  while (fa && fb) {
    fa.read(ba.data(), std::streamsize(ba.size()));
    fb.read(bb.data(), std::streamsize(bb.size()));
    if (fa.gcount() != fb.gcount() || std::memcmp(ba.data(), bb.data(), size_t(fa.gcount())) != 0)
      return false;
  }
  return fa.eof() && fb.eof();
}

// Times per stage name in first-seen order; each run adds its value (stages absent from a run are skipped).
struct Series {
  std::vector<std::pair<std::string, std::vector<double>>> by_name;
  void add(const std::string& name, double v) {
    auto it = std::find_if(by_name.begin(), by_name.end(), [&](const auto& s) { return s.first == name; });
    if (it == by_name.end()) it = by_name.insert(by_name.end(), {name, {}});
    it->second.push_back(v);
  }
  double median_of(const std::string& name) const {
    for (const auto& [k, v] : by_name)
      if (k == name) return median(v);
    return std::nan("");
  }
};

// What one run's stats say: stage_ms in run order, the device total and the top-level stages' sum (stage
// names without ':'; "triangulate: resolve" and the like are parts of "triangulate").
struct RunFigures {
  std::vector<std::pair<std::string, double>> stages;
  double gpu_ms = std::nan("");
  double top_level_ms = 0;
};

RunFigures run_figures(const json& stats) {
  RunFigures f;
  if (stats.contains("stage_ms"))
    for (const auto& [name, v] : stats["stage_ms"].items()) {
      f.stages.emplace_back(name, v.get<double>());
      if (name.find(':') == std::string::npos) f.top_level_ms += v.get<double>();
    }
  if (stats.contains("gpu_stage_ms") && stats["gpu_stage_ms"].contains("total"))
    f.gpu_ms = stats["gpu_stage_ms"]["total"].get<double>();
  return f;
}

json figures_json(const ChildRun& r) {
  RunFigures f = run_figures(r.stats);
  json s = json::object();
  for (const auto& [k, v] : f.stages) s[k] = v;
  json j = {{"wall_ms", r.wall_ms}, {"stage_ms", s}};
  if (!std::isnan(f.gpu_ms)) j["gpu_ms"] = f.gpu_ms;
  return j;
}

// One backend on one row's inputs in one format.
struct Cell {
  std::string format, backend;
  bool ok = true;
  int exit_code = 0;
  std::string error;                     // which run failed and the child's last log line
  ChildRun first;                        // empty caches
  std::vector<double> wall, gpu, other;  // timed runs; other = wall - the top-level stages
  Series stages;
  json runs = json::array();
  std::string device;
  json counts;  // the last run's stats counts (vertices, constraints, triangles, ...)
  std::string output;
  uint64_t output_bytes = 0;
  std::string equal = "-";  // yes / no / - (failed)
};

// The stage a column shows; NaN when the runs have none by that name.
double stage(const Cell& c, const char* name) { return c.stages.median_of(name); }

struct RowPlan {
  uint64_t points, segments;
};

std::vector<RowPlan> plan_rows(const BenchOptions& o) {
  std::vector<uint64_t> sizes;
  for (const std::string& s : o.sizes) sizes.push_back(parse_bench_size(s));
  if (sizes.empty())
    sizes = o.quick ? std::vector<uint64_t>{20000, 200000}
                    : std::vector<uint64_t>{20000, 200000, 2000000, 4000000};
  std::vector<RowPlan> rows;
  for (uint64_t n : sizes) rows.push_back({n, n / 4});
  return rows;
}

std::string self_executable() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this executable (/proc/self/exe): " + ec.message());
  return p.string();
}

// A fresh temp folder (mkdtemp), or --keep's folder.
std::string work_root(const BenchOptions& o) {
  if (!o.keep_dir.empty()) {
    fs::create_directories(o.keep_dir);
    return fs::absolute(o.keep_dir).string();
  }
  std::string tmpl = (fs::temp_directory_path() / "cdtgpu-e2e-XXXXXX").string();
  if (!mkdtemp(tmpl.data()))
    throw std::runtime_error("cannot create a temp folder: " + std::string(std::strerror(errno)));
  return tmpl;
}

// A shell word for a job file line (cli/job_file.hpp): single quotes, a quote inside as '\''.
std::string job_word(const std::string& w) {
  std::string q = "'";
  for (char c : w) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The batch row: a job file of o.batch_jobs copies of the row's run (`--backend auto`), each to its own PLY and
// stats; the last job's stats stand for the row (the first pays the device's start).
struct BatchPlan {
  std::string jobs_file;
  std::vector<std::string> outputs, stats;
};
BatchPlan write_batch_jobs(const BenchOptions& o, const std::string& dir, const E2eFiles& files,
                           const std::string& tag) {
  BatchPlan b;
  b.jobs_file = (fs::path(dir) / ("jobs-" + tag + ".txt")).string();
  std::string text;
  for (int k = 1; k <= o.batch_jobs; ++k) {
    b.outputs.push_back((fs::path(dir) / ("out-" + tag + "-" + std::to_string(k) + ".ply")).string());
    b.stats.push_back((fs::path(dir) / ("stats-" + tag + "-" + std::to_string(k) + ".json")).string());
    for (const std::string& in : files.inputs) text += job_word(in) + " ";
    text += "-o " + job_word(b.outputs.back()) + " --stats " + job_word(b.stats.back()) + "\n";
  }
  write_file_atomically(b.jobs_file, [&](std::ostream& out) { out << text; });
  return b;
}

// Runs one backend on one format's inputs: first run (empty caches), warm-up, timed runs. "batch": one
// `cdtgpu batch` of o.batch_jobs jobs per run, its wall divided by the jobs.
Cell run_cell(const BenchOptions& o, const std::string& binary, const std::string& dir, const E2eFiles& files,
              const std::string& format, const std::string& backend) {
  Cell c;
  c.format = format;
  c.backend = backend;
  const std::string tag = format + "-" + backend;
  const bool batch = backend == "batch";
  c.output = (fs::path(dir) / ("out-" + tag + ".ply")).string();
  std::string stats = (fs::path(dir) / ("stats-" + tag + ".json")).string();
  const std::string log = (fs::path(dir) / ("log-" + tag + ".txt")).string();
  std::vector<std::string> argv{binary, "triangulate"};
  argv.insert(argv.end(), files.inputs.begin(), files.inputs.end());
  argv.insert(argv.end(), {"-o", c.output, "--stats", stats, "-q", "--backend", backend});
  BatchPlan plan;
  if (batch) {
    plan = write_batch_jobs(o, dir, files, tag);
    c.output = plan.outputs.front();
    stats = plan.stats.back();
    argv = {binary, "batch", plan.jobs_file, "-q"};
  }
  const double jobs = batch ? o.batch_jobs : 1;
  if (!o.device.empty()) argv.insert(argv.end(), {"--device", o.device});

  // Empty caches: the driver's shader caches and ours (under XDG_CACHE_HOME) start from nothing.
  const fs::path caches = fs::path(dir) / ("caches-" + tag);
  fs::remove_all(caches);
  std::map<std::string, std::string> cold;
  for (const char* var : {"XDG_CACHE_HOME", "__GL_SHADER_DISK_CACHE_PATH", "MESA_SHADER_CACHE_DIR"}) {
    const fs::path p = caches / var;
    fs::create_directories(p);
    cold[var] = p.string();
  }
  auto failed = [&](const char* which, const ChildRun& r) {
    c.ok = false;
    c.exit_code = r.exit_code;
    c.error = std::string(which) + " run: exit code " + std::to_string(r.exit_code) + ": " + last_line(r.log);
    spdlog::error("{}: {} {}: {}", dir, format, backend, c.error);
  };
  if (o.first_run) {
    c.first = spawn_child(argv, cold, log, stats);
    if (!o.keep_dir.empty()) fs::copy_file(log, log + ".first", fs::copy_options::overwrite_existing);
    if (c.first.exit_code != 0) {
      failed("first", c.first);
      fs::remove_all(caches);
      return c;
    }
  }
  fs::remove_all(caches);
  ChildRun warm = spawn_child(argv, {}, log, stats);
  if (warm.exit_code != 0) {
    failed("warm-up", warm);
    return c;
  }
  for (int i = 0; i < o.runs; ++i) {
    ChildRun r = spawn_child(argv, {}, log, stats);
    if (r.exit_code != 0) {
      failed("timed", r);
      return c;
    }
    RunFigures f = run_figures(r.stats);
    c.wall.push_back(r.wall_ms / jobs);
    // A batch's stages overlap one another's: wall minus one job's stages says nothing there.
    if (!batch) c.other.push_back(r.wall_ms - f.top_level_ms);
    if (!std::isnan(f.gpu_ms)) c.gpu.push_back(f.gpu_ms);
    for (const auto& [name, ms] : f.stages) c.stages.add(name, ms);
    c.runs.push_back(figures_json(r));
    if (r.stats.contains("device")) c.device = r.stats["device"].get<std::string>();
    if (r.stats.contains("counts")) c.counts = r.stats["counts"];
  }
  std::error_code ec;
  c.output_bytes = fs::file_size(c.output, ec);
  for (size_t k = 1; k < plan.outputs.size(); ++k) {  // every job of the batch wrote the first job's bytes
    if (!same_bytes(plan.outputs[0], plan.outputs[k])) {
      c.ok = false;
      c.error = "batch job " + std::to_string(k + 1) + ": " + plan.outputs[k] + " differs from job 1's";
      spdlog::error("{}: {}", dir, c.error);
    }
    if (o.keep_dir.empty()) fs::remove(plan.outputs[k]);
  }
  return c;
}

json cell_json(const Cell& c, uint64_t input_bytes, bool first_run) {
  json j;
  j["format"] = c.format;
  j["backend"] = c.backend;
  j["ok"] = c.ok;
  if (!c.ok) {
    j["exit_code"] = c.exit_code;
    j["error"] = c.error;
    return j;
  }
  if (!c.device.empty()) j["device"] = c.device;
  j["wall_median_ms"] = median(c.wall);
  if (first_run) j["first_run"] = figures_json(c.first);
  json sm = json::object();
  for (const auto& [name, v] : c.stages.by_name) sm[name] = median(v);
  j["stage_median_ms"] = sm;
  j["other_median_ms"] = median(c.other);
  if (!c.gpu.empty()) j["gpu_median_ms"] = median(c.gpu);
  const double read = stage(c, "read");
  if (read > 0) j["read_mb_per_s"] = double(input_bytes) / 1e6 / (read / 1e3);
  j["output_bytes"] = c.output_bytes;
  j["counts"] = c.counts;
  j["bytes_equal"] = c.equal == "yes";
  j["runs"] = c.runs;
  return j;
}

}  // namespace

int run_e2e(const BenchOptions& o) {
  const std::vector<RowPlan> rows = plan_rows(o);
  const std::vector<std::string> backends =
      o.backends.empty() ? std::vector<std::string>{"auto", "gpu", "cgal", "batch"} : o.backends;
  const std::vector<std::string> formats =
      o.formats.empty() ? std::vector<std::string>{"text", "shp"} : o.formats;
  for (const std::string& f : formats)
    if (f != "text" && f != "shp" && f != "las" && f != "asc" && f != "tif")
      throw UsageError("--formats: text, shp, las, asc or tif, got '" + f + "'");
  const std::string binary = o.binary.empty() ? self_executable() : fs::absolute(o.binary).string();
  if (access(binary.c_str(), X_OK) != 0) throw UsageError("--binary: not an executable: " + binary);
  const std::string root = work_root(o);
  struct RemoveTemp {  // also when a row throws
    std::string path;
    ~RemoveTemp() {
      std::error_code ec;
      if (!path.empty()) fs::remove_all(path, ec);
    }
  } remove_temp{o.keep_dir.empty() ? root : std::string()};
  const std::string cpu = bench_cpu_model(), date = bench_utc_now();
  const unsigned threads = std::thread::hardware_concurrency();

  std::printf("cdtgpu bench --table e2e, %s\n", date.c_str());
  std::printf("CPU: %s, %u hardware threads\n", cpu.c_str(), threads);
  std::printf("child: %s triangulate INPUTS -o OUT.ply --stats S.json -q --backend B\n", binary.c_str());
  if (std::find(backends.begin(), backends.end(), "batch") != backends.end())
    std::printf("batch: %s batch JOBS -q, JOBS = %d lines `INPUTS -o OUT-k.ply --stats S-k.json` (auto); wall = "
                "spawn to exit / %d, stages = the last job's\n",
                binary.c_str(), o.batch_jobs, o.batch_jobs);
  std::printf(
      "wall = spawn to exit, median of %d runs after 1 warm-up; first = one run before, with empty "
      "shader and pipeline caches; stages from the child's --stats (medians); other = wall - the stages "
      "(process start, Vulkan device, exit); MB = input bytes the readers read; equal = the PLY is "
      "byte-identical to the row's first of its kind (text and shp; las; asc and tif: a DEM grid of about as many "
      "cells); seed %llu\n\n",
      o.runs, static_cast<unsigned long long>(o.seed));
  std::printf("%9s %9s %7s %-5s %-7s %9s %9s %8s %9s %8s %8s %8s %8s %8s %8s %5s\n", "points", "segments",
              "MB", "input", "backend", "wall ms", "first ms", "read ms", "read MB/s", "project", "prepare",
              "triang.", "write", "other", "GPU ms", "equal");
  std::fflush(stdout);

  json jrows = json::array();
  std::string device;
  int failures = 0;
  for (const RowPlan& row : rows) {
    const fs::path dir = fs::path(root) / std::to_string(row.points);
    fs::create_directories(dir);
    auto tg = Clock::now();
    const E2eWorkload w = e2e_workload(row.points, row.segments, o.seed);
    const double generate_ms = ms_since(tg);
    // The first PLY of each kind of input: every other of the kind must equal it. Text and shapefiles hold
    // the same points; LAS's may differ by an ulp (bench/e2e_workload.hpp); the grids hold the DEM's cells.
    std::map<std::string, std::string> references;
    const bool grids = std::find_if(formats.begin(), formats.end(), [](const std::string& f) {
                         return f == "asc" || f == "tif";
                       }) != formats.end();
    const Raster dem = grids ? e2e_dem(row.points) : Raster{};
    json jformats = json::array();
    for (const std::string& format : formats) {
      auto tw = Clock::now();
      const fs::path fdir = dir / format;
      fs::create_directories(fdir);
      const bool grid = format == "asc" || format == "tif";
      const E2eFiles files = format == "text" ? write_e2e_text(w, fdir.string())
                             : format == "shp" ? write_e2e_shapefiles(w, fdir.string())
                             : format == "las" ? write_e2e_las(w, fdir.string())
                                               : write_e2e_grid(w, dem, format == "tif", fdir.string());
      const double write_ms = ms_since(tw);
      const uint64_t points = grid ? dem.z.size() : w.input.points.size();
      std::string& reference = references[grid ? "grid" : format == "las" ? "las" : "points"];
      json jcells = json::array();
      for (const std::string& backend : backends) {
        Cell c = run_cell(o, binary, fdir.string(), files, format, backend);
        if (c.ok) {
          if (reference.empty()) {
            reference = c.output;
            c.equal = "yes";
          } else {
            c.equal = same_bytes(reference, c.output) ? "yes" : "no";
            if (c.equal == "no") {
              spdlog::error("{} points, {} {}: {} differs from {}", row.points, format, backend, c.output,
                            reference);
              ++failures;
            }
            if (o.keep_dir.empty())
              fs::remove(c.output);  // outputs reach hundreds of MB; the reference stays
          }
          if (device.empty()) device = c.device;
        } else {
          ++failures;
        }
        const double read = stage(c, "read");
        const double mbps = read > 0 ? double(files.bytes) / 1e6 / (read / 1e3) : std::nan("");
        if (c.ok)
          std::printf("%9llu %9llu %7.1f %-5s %-7s %9s %9s %8s %9s %8s %8s %8s %8s %8s %8s %5s\n",
                      static_cast<unsigned long long>(points),
                      static_cast<unsigned long long>(w.segments), double(files.bytes) / 1e6, format.c_str(),
                      backend.c_str(), fmt(median(c.wall)).c_str(),
                      o.first_run ? fmt(c.first.wall_ms).c_str() : "-", fmt(read).c_str(), fmt(mbps).c_str(),
                      fmt(stage(c, "project")).c_str(), fmt(stage(c, "prepare")).c_str(),
                      fmt(stage(c, "triangulate")).c_str(), fmt(stage(c, "write")).c_str(),
                      fmt(median(c.other)).c_str(), c.gpu.empty() ? "-" : fmt(median(c.gpu)).c_str(),
                      c.equal.c_str());
        else
          std::printf("%9llu %9llu %7.1f %-5s %-7s FAILED: %s\n", static_cast<unsigned long long>(points),
                      static_cast<unsigned long long>(w.segments), double(files.bytes) / 1e6, format.c_str(),
                      backend.c_str(), c.error.c_str());
        std::fflush(stdout);
        jcells.push_back(cell_json(c, files.bytes, o.first_run));
      }
      jformats.push_back({{"format", format},
                          {"points", points},
                          {"inputs", files.inputs},
                          {"input_bytes", files.bytes},
                          {"write_inputs_ms", write_ms},
                          {"backends", jcells}});
      if (o.keep_dir.empty())
        for (const std::string& f : files.files) fs::remove(f);
    }
    jrows.push_back({{"points", w.input.points.size()},
                     {"segments", w.segments},
                     {"lines", w.input.lines.size()},
                     {"segments_per_line", w.segments_per_line},
                     {"sources", w.input.sources},
                     {"generate_ms", generate_ms},
                     {"formats", jformats}});
    if (o.keep_dir.empty()) fs::remove_all(dir);
  }

  if (!o.json_path.empty()) {
    json j;
    j["tool"] = "cdtgpu bench --table e2e";
    j["date"] = date;
    j["machine"] = {
        {"cpu", cpu}, {"hardware_threads", threads}, {"gpu", device.empty() ? json() : json(device)}};
    j["binary"] = binary;
    j["command"] = "BINARY triangulate INPUTS -o OUT.ply --stats S.json -q --backend B";
    j["runs"] = o.runs;
    j["warmup_runs"] = 1;
    j["first_run"] = !o.first_run
                         ? json("skipped (--no-first-run)")
                         : "one run before the warm-up with XDG_CACHE_HOME, __GL_SHADER_DISK_CACHE_PATH and "
                           "MESA_SHADER_CACHE_DIR set to fresh empty folders";
    j["wall"] = "posix_spawn to waitpid, steady clock";
    j["seed"] = o.seed;
    j["backends"] = backends;
    j["formats"] = formats;
    j["rows"] = jrows;
    write_file_atomically(o.json_path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
  }
  if (failures) spdlog::error("{} run(s) failed or gave a different PLY", failures);
  return failures ? 1 : 0;
}

}  // namespace cdtgpu
