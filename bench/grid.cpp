// cdtgpu bench --table grid (see grid.hpp).
#include "bench/figures.hpp"
#include "bench/grid.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench/e2e_workload.hpp"
#include "core/cdt_cgal.hpp"
#include "core/contours.hpp"
#include "core/raster.hpp"
#include "core/workloads.hpp"
#include "gpu/contours.hpp"
#include "gpu/primitives.hpp"
#include "gpu/raster.hpp"
#include "gpu/tin.hpp"
#include "io/geotiff.hpp"
#include "io/gis_writers.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;
using figures::Clock;
using figures::median;
using figures::ms_since;
using figures::fmt;
using json = nlohmann::ordered_json;




std::string wkt_of(const std::vector<Contour>& lines) {
  std::ostringstream out;
  write_contours_wkt(lines, out);
  return out.str();
}

bool same_grid(const Raster& a, const Raster& b) {
  if (a.z.size() != b.z.size()) return false;
  for (size_t i = 0; i < a.z.size(); ++i)
    if (std::bit_cast<uint64_t>(a.z[i]) != std::bit_cast<uint64_t>(b.z[i])) return false;
  return true;
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

// `cdtgpu triangulate` with the grid and contours as a child process (through the shell): wall clock, exit
// code and stats.
struct Child {
  double wall_ms = 0;
  int code = 0;
  json stats;
};

Child run_child(const std::string& binary, const std::vector<std::string>& inputs, const std::string& dir,
                const std::string& backend, double cell, double interval) {
  const std::string out = (fs::path(dir) / backend).string();
  std::string cmd = quote(binary) + " triangulate";
  for (const std::string& in : inputs) cmd += " " + quote(in);
  char numbers[128];
  std::snprintf(numbers, sizeof numbers, " --cell %.17g --interval %.17g", cell, interval);
  cmd += " --crs none -q --backend " + backend + " -o " + quote(out + ".ply") + " --grid-out " +
         quote(out + ".asc") + numbers + " --contours-out " + quote(out + ".wkt") + " --stats " +
         quote(out + ".json") + " > " + quote(out + ".log") + " 2>&1";
  Child c;
  const auto t0 = Clock::now();
  const int status = std::system(cmd.c_str());
  c.wall_ms = ms_since(t0);
  c.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (c.code == 0) c.stats = json::parse(std::ifstream(out + ".json"));
  return c;
}

double stage(const json& stats, const char* name) {
  return stats.contains("stage_ms") && stats["stage_ms"].contains(name)
             ? stats["stage_ms"][name].get<double>()
             : std::nan("");
}

}  // namespace

int run_grid(const BenchOptions& o) {
  std::vector<uint64_t> sizes;
  for (const std::string& s : o.sizes) sizes.push_back(parse_bench_size(s));
  if (sizes.empty()) sizes = {o.quick ? 50000u : 1000000u};
  const uint64_t cells = o.grid_cells ? o.grid_cells : (o.quick ? 1000 : 10000);
  if (cells < 2) throw std::invalid_argument("--grid-cells must be at least 2");

  gpu::ContextOptions co;
  co.device = o.device;
  gpu::Context ctx = gpu::create_context(co);
  gpu::Primitives prims(ctx);
  gpu::GpuRasteriser rasteriser(ctx, prims);
  gpu::GpuContourer contourer(ctx, prims);
  const std::string binary = o.binary.empty() ? fs::read_symlink("/proc/self/exe").string() : o.binary;

  std::printf("cdtgpu bench --table grid, %s\n", bench_utc_now().c_str());
  std::printf("CPU: %s, %u hardware threads\n", bench_cpu_model().c_str(),
              std::thread::hardware_concurrency());
  std::printf("GPU: %s, driver %s %s\n", ctx.info.name.c_str(), ctx.info.driver_name.c_str(),
              ctx.info.driver_info.c_str());
  std::printf(
      "TIN: the terrain workload (DEM grid 10 m apart + contour lines), CGAL backend; grid: %llu cells on "
      "the "
      "long side; contours: 100 levels over the z range\n",
      static_cast<unsigned long long>(cells));
  std::printf(
      "in-process: median of %d runs after 1 warm-up (CPU: all cores; GPU: wall clock of the call, "
      "download included, and its device timestamps); process: `cdtgpu triangulate ... --grid-out "
      "--contours-out` wall clock after 1 warm-up\n\n",
      o.runs);
  std::printf(
      "| points | triangles | grid cells | CPU grid ms | GPU grid ms (device) | TIN upload ms | CPU contours "
      "ms "
      "| GPU contours ms (device, host chaining) | lines | same | process cgal ms (grid, write) | process "
      "gpu ms (grid, write) | .asc write ms | .tif write ms (MB) | .tif read ms "
      "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);

  json rows = json::array();
  int failures = 0;
  for (const uint64_t n : sizes) {
    TerrainOptions topt;
    topt.grid = uint32_t(std::max(2.0, std::round(std::sqrt(double(n)))));
    topt.seed = o.seed;
    const InputSet in = terrain_workload(topt);
    const Mesh mesh = triangulate_cgal(prepare(in)).mesh;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, z0 = INFINITY, z1 = -INFINITY;
    for (const Point3& p : mesh.vertices) {
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
      z0 = std::min(z0, p.z), z1 = std::max(z1, p.z);
    }
    const double cell = std::max(x1 - x0, y1 - y0) / double(cells - 1);
    const double interval = (z1 - z0) / 100;
    const GridSpec spec = grid_for(mesh, cell, uint64_t(1) << 34);

    std::vector<double> cpu_grid, gpu_grid, gpu_grid_dev, upload, cpu_lines, gpu_lines, gpu_lines_dev, chain;
    Raster cpu_r, gpu_r;
    std::vector<Contour> cpu_c, gpu_c;
    for (int run = 0; run <= o.runs; ++run) {  // run 0 is the warm-up
      auto t = Clock::now();
      cpu_r = rasterise(mesh, spec);
      if (run) cpu_grid.push_back(ms_since(t));
      t = Clock::now();
      const gpu::DeviceTin tin = gpu::upload_tin(ctx, mesh);
      if (run) upload.push_back(ms_since(t));
      t = Clock::now();
      gpu_r = rasteriser.rasterise(tin, spec);
      if (run) gpu_grid.push_back(ms_since(t)), gpu_grid_dev.push_back(rasteriser.gpu_ms);
      t = Clock::now();
      cpu_c = contour_lines(mesh, interval);
      if (run) cpu_lines.push_back(ms_since(t));
      t = Clock::now();
      gpu_c = contourer.lines(tin, mesh, interval);
      if (run)
        gpu_lines.push_back(ms_since(t)), gpu_lines_dev.push_back(contourer.gpu_ms),
            chain.push_back(contourer.chain_ms);
    }
    const bool same = same_grid(cpu_r, gpu_r) && wkt_of(cpu_c) == wkt_of(gpu_c);
    gpu_r = Raster{};
    const fs::path dir = fs::temp_directory_path() / ("cdtgpu_bench_grid_" + std::to_string(::getpid()));
    fs::create_directories(dir);

    // The grid's files, in-process: ESRI ASCII and GeoTIFF written (synced, renamed), the GeoTIFF read back.
    std::vector<double> asc_write, tif_write, tif_read;
    uint64_t tif_bytes = 0;
    Crs no_crs;
    for (int run = 0; run <= o.runs; ++run) {
      auto t = Clock::now();
      write_ascii_grid_file(cpu_r, no_crs, (dir / "w.asc").string());
      if (run) asc_write.push_back(ms_since(t));
      fs::remove(dir / "w.asc");
      t = Clock::now();
      write_geotiff_grid_file(cpu_r, no_crs, (dir / "w.tif").string());
      if (run) tif_write.push_back(ms_since(t));
      tif_bytes = fs::file_size(dir / "w.tif");
      {
        t = Clock::now();
        InputSet back;
        read_geotiff((dir / "w.tif").string(), back);
        if (run) tif_read.push_back(ms_since(t));  // the read alone: 2.4 GB of vertices are freed after
      }
    }
    fs::remove(dir / "w.tif");
    cpu_r = Raster{};

    // The whole process, files in, mesh + grid + contours out.
    E2eWorkload w;
    w.input = in;
    const E2eFiles files = write_e2e_text(w, dir.string());
    Child proc[2];
    const char* backends[2] = {"cgal", "gpu"};
    for (int b = 0; b < 2; ++b) {
      run_child(binary, files.inputs, dir.string(), backends[b], cell, interval);  // warm-up
      proc[b] = run_child(binary, files.inputs, dir.string(), backends[b], cell, interval);
      if (proc[b].code != 0)
        std::fprintf(stderr, "cdtgpu triangulate --backend %s failed (exit %d), see %s\n", backends[b],
                     proc[b].code, (dir / (std::string(backends[b]) + ".log")).c_str());
    }
    const std::string cmp = "cmp -s " + quote((dir / "cgal.asc").string()) + " " +
                            quote((dir / "gpu.asc").string()) + " && cmp -s " +
                            quote((dir / "cgal.wkt").string()) + " " + quote((dir / "gpu.wkt").string());
    const bool same_files = proc[0].code == 0 && proc[1].code == 0 && std::system(cmp.c_str()) == 0;
    if (o.keep_dir.empty()) fs::remove_all(dir);
    if (!same || !same_files) ++failures;

    auto process = [&](const Child& c) {
      if (c.code != 0) return std::string("failed");
      return fmt(c.wall_ms) + " (" + fmt(stage(c.stats, "grid")) + ", " + fmt(stage(c.stats, "write")) + ")";
    };
    std::printf("| %llu | %zu | %llu x %llu | %s | %s (%s) | %s | %s | %s (%s, %s) | %zu | %s | %s | %s | %s | %s (%.1f) | %s |\n",
                static_cast<unsigned long long>(mesh.vertices.size()), mesh.triangles.size(),
                static_cast<unsigned long long>(spec.ncols), static_cast<unsigned long long>(spec.nrows),
                fmt(median(cpu_grid)).c_str(), fmt(median(gpu_grid)).c_str(),
                fmt(median(gpu_grid_dev)).c_str(), fmt(median(upload)).c_str(),
                fmt(median(cpu_lines)).c_str(), fmt(median(gpu_lines)).c_str(),
                fmt(median(gpu_lines_dev)).c_str(), fmt(median(chain)).c_str(), cpu_c.size(),
                same && same_files ? "yes" : (same ? "files differ" : "NO"), process(proc[0]).c_str(),
                process(proc[1]).c_str(), fmt(median(asc_write)).c_str(), fmt(median(tif_write)).c_str(),
                double(tif_bytes) / 1e6, fmt(median(tif_read)).c_str());
    std::fflush(stdout);
    rows.push_back(
        {{"points", mesh.vertices.size()},
         {"triangles", mesh.triangles.size()},
         {"ncols", spec.ncols},
         {"nrows", spec.nrows},
         {"cell", cell},
         {"interval", interval},
         {"cpu_grid_ms", cpu_grid},
         {"gpu_grid_ms", gpu_grid},
         {"gpu_grid_device_ms", gpu_grid_dev},
         {"tin_upload_ms", upload},
         {"cpu_contours_ms", cpu_lines},
         {"gpu_contours_ms", gpu_lines},
         {"gpu_contours_device_ms", gpu_lines_dev},
         {"gpu_contours_host_chaining_ms", chain},
         {"contour_lines", cpu_c.size()},
         {"same_in_process", same},
         {"asc_write_ms", asc_write},
         {"tif_write_ms", tif_write},
         {"tif_bytes", tif_bytes},
         {"tif_read_ms", tif_read},
         {"same_files", same_files},
         {"process_cgal", {{"wall_ms", proc[0].wall_ms}, {"exit", proc[0].code}, {"stats", proc[0].stats}}},
         {"process_gpu", {{"wall_ms", proc[1].wall_ms}, {"exit", proc[1].code}, {"stats", proc[1].stats}}}});
  }
  if (!o.json_path.empty()) {
    json j = {{"table", "grid"},
              {"date", bench_utc_now()},
              {"cpu", bench_cpu_model()},
              {"gpu", ctx.info.name + ", driver " + ctx.info.driver_name + " " + ctx.info.driver_info},
              {"grid_cells", cells},
              {"runs", o.runs},
              {"seed", o.seed},
              {"rows", rows}};
    std::ofstream(o.json_path) << j.dump(2) << "\n";
  }
  return failures ? 1 : 0;
}

}  // namespace cdtgpu
