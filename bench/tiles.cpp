#include "bench/tiles.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include <tbb/parallel_for.h>

#include "bench/figures.hpp"
#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/parallel.hpp"
#include "core/resolve.hpp"
#include "core/uninit.hpp"
#include "core/tiles.hpp"
#include "core/tiles_ahead.hpp"
#include "core/workloads.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/check.hpp"
#include "gpu/devices.hpp"
#include "gpu/tile_triangulator.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {
namespace {

using figures::Clock;
using figures::fmt;
using figures::median;
using figures::ms_since;
using json = nlohmann::json;

double peak_rss_gb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB on Linux
}

struct Row {
  std::string mode;  // "single" or "tiled"
  std::string backend;
  std::vector<double> total_ms, resolve_ms, tiles_ms, merge_ms;
  TileStats tiles;
  uint64_t tile_points = 0;
  Mesh mesh;               // the first row's; the others' only until compared with it (keep below)
  uint64_t triangles = 0;  // the mesh's
  bool same = true;        // the first row's mesh, byte for byte
  double timed_ms = -1;    // set by a run that times itself: the bench's own copies left out
};

// One way of triangulating `p`, timed `runs` times after a warm-up (none for a single timed run: CGAL's
// minutes at 16M points).
template <class F>
Row time_row(const std::string& mode, const std::string& backend, int runs, F&& once) {
  Row row;
  row.mode = mode;
  row.backend = backend;
  for (int r = runs > 1 ? -1 : 0; r < runs; ++r) {
    Row one;
    const auto t = Clock::now();
    once(one);
    if (r < 0) continue;
    row.total_ms.push_back(one.timed_ms >= 0 ? one.timed_ms : ms_since(t));
    row.resolve_ms.insert(row.resolve_ms.end(), one.resolve_ms.begin(), one.resolve_ms.end());
    if (mode == "tiled")
      row.tiles_ms.push_back(one.tiles.tiles_ms), row.merge_ms.push_back(one.tiles.merge_ms);
    row.tiles = one.tiles;
    row.tile_points = one.tile_points;
    if (r + 1 == runs) row.mesh = std::move(one.mesh);
  }
  return row;
}

void tiled_once(const PreparedInput& p, uint64_t tile_points, const TileTriangulator& tri, Row& out,
                unsigned in_flight = 0, const TileFinalizer& finalize = {},
                const std::function<void(uint64_t)>& reserve = {}, unsigned ramp = 0, bool in_runs = false) {
  const auto t = Clock::now();
  // As cdtgpu triangulate does: the tiles' staging (and the devices' warm-up) begun before the resolve.
  if (reserve) reserve(tile_staging_points(p.vertices.size(), tile_points));
  TileOptions opt;
  opt.max_tile_points = tile_points;
  opt.tiles_in_flight = in_flight;
  opt.finalize = finalize;
  opt.reserve = reserve;
  opt.ramp = ramp;
  opt.in_runs = in_runs;
  out.tile_points = tile_points;
  if (finalize) {  // a device's tiles check themselves, no resolve unless one has something (core/tiles_ahead.hpp)
    std::optional<OrderedRuns> checked = tiled_cdt_unresolved(p, opt, tri, &out.tiles);
    if (checked) {
      // The mesh's vertices: cdtgpu triangulate moves the prepared ones; `p` serves every run here, so they are
      // copied, untimed. Copied beside the tiles, they took the host's memory from the first tile's gather and
      // staging (16 GB at 1B points), which triangulate does not.
      out.timed_ms = ms_since(t);
      out.resolve_ms.push_back(0);
      resize_unwritten(out.mesh.vertices, p.vertices.size());
      copy_on_all_cores(p.vertices.data(), p.vertices.size(), out.mesh.vertices.data());
      out.mesh.triangles = std::move(*checked).take();
      return;
    }
    out.tiles = TileStats{};
  }
  ResolvedInput in = resolve_constraints(p);
  out.resolve_ms.push_back(ms_since(t));
  CdtResult r = triangulate_tiled(std::move(in), opt, tri, &out.tiles);
  out.timed_ms = ms_since(t);
  gather_triangles(r);
  out.mesh = std::move(r.mesh);
}

// Above kDtEdgesMaxPoints the Delaunay-edge constraints (a CGAL triangulation of half the points, minutes at
// 256M) give way to contour-like chains (add_band_chains, core/workloads.hpp).
constexpr uint64_t kDtEdgesMaxPoints = 20'000'000;

}  // namespace

int run_tiles(const BenchOptions& o) {
  std::vector<uint64_t> sizes;
  for (const auto& s : o.sizes) sizes.push_back(parse_bench_size(s));
  if (sizes.empty())
    sizes = o.quick ? std::vector<uint64_t>{200000} : std::vector<uint64_t>{2000000, 16000000};
  const unsigned threads = std::thread::hardware_concurrency();
  const int cgal_runs = o.cgal_runs > 0 ? o.cgal_runs : o.runs;

  // Each GPU row gets a context of its own, as each `cdtgpu triangulate` run does: the H100's clock drops
  // after seconds without load (the CPU rows) and our bursts do not raise it again (bench/bench.cpp,
  // time_gpu).
  gpu::ContextOptions co;
  co.device = o.device;
  std::string device = "none (--cgal-only)";
  if (o.gpu) {
    const gpu::Context ctx = gpu::create_context(co);
    device = ctx.info.name + ", driver " + ctx.info.driver_name + " " + ctx.info.driver_info;
  }
  std::printf("cdtgpu bench --table tiles, %s\n", bench_utc_now().c_str());
  std::printf("CPU: %s, %u hardware threads\nGPU: %s\n", bench_cpu_model().c_str(), threads, device.c_str());
  std::printf(
      "workload: uniform points + a quarter as many Delaunay-edge constraints (seed %llu), in process; "
      "median of %d runs (single CPU run: %d) after 1 warm-up (none for 1 run); total = resolve + tiles + "
      "merge + canonical order (with --in-runs, GPU tiled rows: the order's spans, the triangles left in the "
      "tiles' runs as cdtgpu triangulate leaves them for a mesh it only writes; GPU tiled rows: their tiles check themselves, no resolve unless one finds a "
      "constraint to split, core/tiles_ahead.hpp; "
      "single runs: the whole backend call); same = the mesh equals the first single run's\n\n",
      static_cast<unsigned long long>(o.seed), o.runs, cgal_runs);
  std::printf("%9s %-6s %-6s %7s %6s %6s %7s %9s %9s %9s %9s %9s %9s %7s %s\n", "points", "mode", "backend",
              "tile", "tiles", "levels", "final%", "merge v", "resolve", "tiles ms", "merge ms", "total ms",
              "vs single", "RSS GB", "same");
  std::fflush(stdout);

  // The device counts of the GPU tiled rows: 0 (the one device --device picks), then 2, 4, ... and all of
  // --devices.
  std::vector<size_t> device_set, gpu_device_counts;
  if (o.gpu) gpu_device_counts.push_back(0);
  if (o.gpu && !o.devices.empty()) {
    device_set = gpu::select_devices(gpu::list_devices(), o.devices, o.device);
    for (size_t k = 2; k < device_set.size(); k *= 2) gpu_device_counts.push_back(k);
    if (device_set.size() > 1) gpu_device_counts.push_back(device_set.size());
    std::printf("GPU tiled rows also on 2 to %zu devices:", device_set.size());
    for (size_t i : device_set) std::printf(" %zu", i);
    std::printf("\n");
  }
  json rows = json::array();
  int failures = 0;
  for (uint64_t n : sizes) {
    InputSet in = uniform_points(n, o.seed);
    if (!o.points_only && n <= kDtEdgesMaxPoints) add_dt_edge_constraints(in, n / 4, 0.5, o.seed);
    if (!o.points_only && n > kDtEdgesMaxPoints) add_band_chains(in);
    const PreparedInput p = prepare(in);
    in = InputSet{};
    std::vector<Row> results;
    // Each row's mesh compared with the first's as it comes, then dropped: at 1B points a mesh is 40 GB, and
    // nine rows' left the later ones short of the host's memory (the output's room not made ahead).
    auto keep = [&](Row r) {
      r.triangles = r.mesh.triangles.size();
      if (!results.empty()) {
        const Mesh& first = results.front().mesh;
        r.same = r.mesh.vertices == first.vertices && r.mesh.triangles == first.triangles;
        r.mesh = Mesh{};
      }
      results.push_back(std::move(r));
    };
    if (n <= o.cgal_max_points)
      keep(
          time_row("single", "cgal", cgal_runs, [&](Row& r) { r.mesh = triangulate_cgal(p).mesh; }));
    uint64_t gpu_single_peak = 0;
    if (o.gpu) {
      const gpu::Context ctx = gpu::create_context(co);
      const gpu::GpuCdt cdt(ctx);
      try {  // a device too small for the whole input refuses it: the tiled rows still run
        keep(time_row("single", "gpu", o.runs, [&](Row& r) {
          gpu::GpuCdtStats gs;
          r.mesh = cdt.triangulate(p, &gs).mesh;
          gpu_single_peak = gs.peak_device_bytes;
        }));
        std::printf("%9s single GPU run: peak device %s MB\n", "",
                    fmt(double(gpu_single_peak) / 1e6).c_str());
      } catch (const gpu::DeviceError& e) {
        std::printf("%9llu single gpu: refused by the device: %s\n", static_cast<unsigned long long>(n),
                    e.what());
        rows.push_back({{"points", n}, {"mode", "single"}, {"backend", "gpu"}, {"refused", e.what()}});
      }
    }
    const uint64_t cpu_tile =
        o.tile_points ? o.tile_points : auto_cpu_tile_points(p.vertices.size(), threads);
    if (cpu_tile && n <= o.cgal_max_points)
      keep(time_row("tiled", "cgal", o.runs,
                                 [&](Row& r) { tiled_once(p, cpu_tile, cgal_tile_triangulator(), r); }));
    // GPU tiles on one device, then on 2, 4, ... of --devices: two tiles in flight a device, as cdtgpu
    // triangulate runs them; without --tile-points, its tiles (auto_gpu_tile_points: a quarter of the input a
    // device, or what the smallest device holds).
    for (size_t k : gpu_device_counts) {
      gpu::TileDevices devices;
      devices.open(k ? std::vector<size_t>(device_set.begin(), device_set.begin() + std::min(k, device_set.size()))
                     : gpu::select_devices(gpu::list_devices(), "", o.device),
                   co);
      const std::vector<const gpu::GpuCdt*>& users = devices.cdts();
      const uint64_t gpu_tile =
          o.tile_points ? o.tile_points
                        : auto_gpu_tile_points(p.vertices.size(), devices.max_tile_points(), users.size());
      gpu::GpuCdtStats sum;
      const gpu::GpuTiles tri = gpu::gpu_tiles(users, &sum);
      // One row a ramp of --tile-ramps (TileOptions::ramp), each named by it; without it, cdtgpu triangulate's.
      const unsigned ramp_of_cli = gpu::tile_ramp(users, gpu_tile);
      for (const unsigned ramp : o.tile_ramps.empty() ? std::vector<unsigned>{ramp_of_cli} : o.tile_ramps) {
        const std::string backend = (users.size() == 1 ? "gpu" : "gpu-" + std::to_string(users.size())) +
                                    (o.tile_ramps.empty() ? "" : " ramp " + std::to_string(ramp));
        const double memory_before = gpu::memory_ms();
        keep(time_row("tiled", backend, o.runs, [&](Row& r) {
          sum = gpu::GpuCdtStats{};
          tiled_once(p, gpu_tile, tri.triangulate, r, unsigned(o.tiles_in_flight * users.size()), tri.finalize,
                     tri.reserve, ramp, o.in_runs);
          // Through the bench's own work between runs (~1.3 s at 1B points: the result checked and freed), which
          // cdtgpu triangulate does not have, the devices' clocks fell, and two runs in four began at about half
          // clock (session 68); triangulate holds them up through its prepare.
          tri.hold_clocks();
        }));
        std::string parts;
        for (const auto& [name, ms] : sum.wall_ms) parts += " " + name + " " + fmt(ms);
        std::string gpu_parts;
        for (const auto& [name, ms] : sum.gpu_ms) gpu_parts += " " + name + " " + fmt(ms);
        std::printf(
            "%9s last tiled %s run, the tiles' calls summed: GPU %s ms:%s; wall %s ms:%s; peak device %s MB; device "
            "buffers allocated and freed in %s ms (all runs, all threads)\n", "",
            backend.c_str(), fmt(sum.gpu_total_ms).c_str(), gpu_parts.c_str(), fmt(sum.wall_total_ms).c_str(), parts.c_str(),
            fmt(double(sum.peak_device_bytes) / 1e6).c_str(), fmt(gpu::memory_ms() - memory_before).c_str());
      }
    }
    if (results.empty()) continue;
    std::map<std::string, double> single_ms;
    for (Row& r : results) {
      const bool is_reference = &r == &results.front();
      if (!r.same) ++failures;
      const double total = median(r.total_ms);
      if (r.mode == "single") single_ms[r.backend] = total;
      const bool tiled = r.mode == "tiled";
      const double final_share =
          tiled && r.triangles ? 100.0 * double(r.tiles.final_triangles) / double(r.triangles)
              : std::nan("");
      const double vs = tiled && single_ms.count(r.backend) ? single_ms[r.backend] / total : std::nan("");
      const double rss = peak_rss_gb();
      std::printf("%9llu %-6s %-6s %7s %6s %6s %7s %9s %9s %9s %9s %9s %9s %7.1f %s\n",
                  static_cast<unsigned long long>(n), r.mode.c_str(), r.backend.c_str(),
                  tiled ? std::to_string(r.tile_points).c_str() : "-",
                  tiled ? std::to_string(r.tiles.tiles).c_str() : "-",
                  tiled ? std::to_string(r.tiles.levels).c_str() : "-", fmt(final_share).c_str(),
                  tiled ? std::to_string(r.tiles.merge_vertices).c_str() : "-",
                  fmt(median(r.resolve_ms)).c_str(), fmt(median(r.tiles_ms)).c_str(),
                  fmt(median(r.merge_ms)).c_str(), fmt(total).c_str(), fmt(vs, 2).c_str(), rss,
                  is_reference ? "(ref)"
                  : r.same     ? "yes"
                               : "NO");
      if (tiled)
        std::printf(
            "%9s last run: plan %s ms, tile CDTs %s ms and the tiles' other work %s ms (thread sums; gather %s, "
            "final test and border %s), merge input %s ms, keeping the merge's triangles %s ms, canonical order %s ms\n",
            "", fmt(r.tiles.plan_ms).c_str(), fmt(r.tiles.tile_cdt_thread_ms).c_str(),
            fmt(r.tiles.tile_other_thread_ms).c_str(), fmt(r.tiles.tile_gather_thread_ms).c_str(),
            fmt(r.tiles.tile_final_thread_ms).c_str(), fmt(r.tiles.merge_input_ms).c_str(),
            fmt(r.tiles.keep_ms).c_str(), fmt(r.tiles.order_ms).c_str());
      std::fflush(stdout);
      rows.push_back({{"points", n},
                      {"vertices", p.vertices.size()},
                      {"constraints", p.constraints.size()},
                      {"mode", r.mode},
                      {"backend", r.backend},
                      {"tile_points", r.tile_points},
                      {"tiles", r.tiles.tiles},
                      {"levels", r.tiles.levels},
                      {"final_triangles", r.tiles.final_triangles},
                      {"triangles", r.triangles},
                      {"merge_vertices", r.tiles.merge_vertices},
                      {"merge_segments", r.tiles.merge_segments},
                      {"total_ms", r.total_ms},
                      {"resolve_ms", r.resolve_ms},
                      {"tiles_ms", r.tiles_ms},
                      {"merge_ms", r.merge_ms},
                      {"peak_rss_gb_after", rss},
                      {"reference", is_reference},
                      {"same", r.same},
                      {"last_run_parts_ms",
                       {{"plan", r.tiles.plan_ms},
                        {"tile_cdt_thread_sum", r.tiles.tile_cdt_thread_ms},
                        {"tile_other_thread_sum", r.tiles.tile_other_thread_ms},
                        {"tile_gather_thread_sum", r.tiles.tile_gather_thread_ms},
                        {"tile_final_thread_sum", r.tiles.tile_final_thread_ms},
                        {"merge_input", r.tiles.merge_input_ms},
                        {"keep", r.tiles.keep_ms},
                        {"canonical_order", r.tiles.order_ms}}}});
    }
  }
  if (!o.json_path.empty()) {
    json j{{"table", "tiles"},       {"date", bench_utc_now()}, {"cpu", bench_cpu_model()},
           {"threads", threads},     {"device", device},        {"runs", o.runs},
           {"cgal_runs", cgal_runs}, {"seed", o.seed},          {"rows", rows}};
    write_file_atomically(o.json_path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
  }
  if (failures) std::printf("\n%d tiled or single run(s) differ from the first single run\n", failures);
  return failures ? 1 : 0;
}

}  // namespace cdtgpu
