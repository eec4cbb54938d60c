// The peer table: our GPU stages beside gDel2D's (Cao, Nanjappa et al., CUDA) on identical inputs. Per row the
// e2e workload (bench/e2e_workload.hpp: uniform points + x-monotone contour-like lines) is prepared once; its
// vertices and constraint segments go to gDel2D as its binary input (BASE.vtx: int count + double pairs,
// BASE.cst: int count + int pairs), so both triangulate the same vertices and the same segments.
#include "bench/figures.hpp"
#include "bench/peer.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "bench/child.hpp"
#include "bench/e2e_workload.hpp"
#include "core/canonical.hpp"
#include "core/error.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using figures::median;

std::string fmt(double v) { return figures::fmt(v, 2); }



struct Row {
  uint64_t points = 0, segments = 0;
};

// "2M+500K" -> 2000000 points, 500000 segments; "8M" or "8M+0": no constraints.
Row parse_row(const std::string& s) {
  const size_t plus = s.find('+');
  Row r;
  r.points = parse_bench_size(s.substr(0, plus));
  if (plus != std::string::npos && s.substr(plus + 1) != "0") r.segments = parse_bench_size(s.substr(plus + 1));
  return r;
}

void write_gdel2d_input(const PreparedInput& p, const std::string& base) {
  const int n = static_cast<int>(p.vertices.size()), m = static_cast<int>(p.constraints.size());
  std::ofstream vtx(base + ".vtx", std::ios::binary), cst(base + ".cst", std::ios::binary);
  std::vector<double> xy(2 * size_t(n));
  for (int i = 0; i < n; ++i) xy[2 * i] = p.vertices[i].x, xy[2 * i + 1] = p.vertices[i].y;
  vtx.write(reinterpret_cast<const char*>(&n), 4);
  vtx.write(reinterpret_cast<const char*>(xy.data()), std::streamsize(xy.size() * 8));
  std::vector<int> ab(2 * size_t(m));
  for (int i = 0; i < m; ++i) ab[2 * i] = int(p.constraints[i][0]), ab[2 * i + 1] = int(p.constraints[i][1]);
  cst.write(reinterpret_cast<const char*>(&m), 4);
  cst.write(reinterpret_cast<const char*>(ab.data()), std::streamsize(ab.size() * 4));
  if (!vtx || !cst) throw std::runtime_error("cannot write " + base + ".vtx/.cst");
}

// gDel2D prints per run "TIME: total(init, split, flip, relocate, sort, constraint, out)" in ms; compute is
// total - out (the output copy to the host), as gDel2D's paper reports it.
struct PeerTimes {
  std::vector<double> compute, constraints;
};

PeerTimes parse_gdel2d(const std::string& log) {
  static const std::regex line(R"(TIME: ([0-9.]+)\(([0-9.]+), ([0-9.]+), ([0-9.]+), ([0-9.]+), ([0-9.]+), ([0-9.]+), ([0-9.]+)\))");
  PeerTimes t;
  for (std::sregex_iterator it(log.begin(), log.end(), line), end; it != end; ++it) {
    const double total = std::stod((*it)[1]), constraint = std::stod((*it)[7]), out = std::stod((*it)[8]);
    t.compute.push_back(total - out);
    t.constraints.push_back(constraint);
  }
  return t;
}

// Our GPU backend on a context of its own (as bench.cpp's time_gpu, for the same SM clock reason): one warm-up,
// then `runs` runs; GPU stage times grouped as Delaunay / constraints / canonical order.
struct OurTimes {
  std::vector<double> gpu, dt, cdt, canonical, wall;
  std::vector<std::pair<std::string, std::vector<double>>> stages;
  Mesh mesh;
  uint64_t peak_device_bytes = 0;
  gpu::ConstraintStats last;  // of the last run
};

OurTimes time_ours(const gpu::ContextOptions& co, const PreparedInput& p, int runs) {
  gpu::Context ctx = gpu::create_context(co);
  gpu::GpuCdt cdt(ctx);
  // Tooling switch: timestamps around every constraint kernel and round (their barriers cost time).
  const char* profile = std::getenv("CDTGPU_CDT_PROFILE_KERNELS");
  cdt.constraint_options.profile_kernels = profile && std::string(profile) == "1";
  OurTimes t;
  cdt.triangulate(p);
  for (int r = 0; r < runs; ++r) {
    gpu::GpuCdtStats s;
    CdtResult res = cdt.triangulate(p, &s);
    double dt = 0, con = 0, canon = 0;
    for (const auto& [name, ms] : s.gpu_ms) {
      (name.rfind("dt ", 0) == 0 ? dt : name.rfind("cdt ", 0) == 0 ? con : canon) += ms;
      auto it = std::find_if(t.stages.begin(), t.stages.end(), [&](const auto& e) { return e.first == name; });
      if (it == t.stages.end()) it = t.stages.insert(t.stages.end(), {name, {}});
      it->second.push_back(ms);
    }
    t.gpu.push_back(s.gpu_total_ms);
    t.dt.push_back(dt);
    t.cdt.push_back(con);
    t.canonical.push_back(canon);
    t.wall.push_back(s.wall_total_ms);
    t.peak_device_bytes = std::max(t.peak_device_bytes, s.peak_device_bytes);
    if (r + 1 == runs) t.mesh = std::move(res.mesh), t.last = s.constraints;
  }
  return t;
}

}  // namespace

int run_peer(const BenchOptions& o) {
  std::vector<Row> rows;
  for (const std::string& s : o.rows) rows.push_back(parse_row(s));
  if (rows.empty())
    for (const char* s : {"2M", "8M", "2M+500K", "2M+1M", "4M+1M"}) rows.push_back(parse_row(s));
  if (!o.peer.empty() && !fs::exists(o.peer)) throw UsageError("--peer: no such executable: " + o.peer);
  const std::string dir = (fs::temp_directory_path() / "cdtgpu-peer").string();
  fs::create_directories(dir);
  gpu::ContextOptions co;
  co.device = o.device;
  std::string device;
  {
    gpu::Context ctx = gpu::create_context(co);
    device = ctx.info.name + ", driver " + ctx.info.driver_name + " " + ctx.info.driver_info;
  }
  const int cgal_runs = o.cgal_runs > 0 ? o.cgal_runs : 1;
  std::printf("cdtgpu bench --table peer, %s\nGPU: %s\npeer: %s\n", bench_utc_now().c_str(), device.c_str(),
              o.peer.empty() ? "none (--peer not given)" : o.peer.c_str());
  std::printf("gDel2D: median of %d runs after 1 warm-up, compute = its total - its output copy; cdtgpu: GPU "
              "timestamps (DT / constraints / canonical order), median of %d runs after 1 warm-up; CGAL: %d run(s) "
              "up to %llu points, the triangles compared\n\n",
              o.runs, o.runs, cgal_runs, static_cast<unsigned long long>(o.cgal_max_points));
  std::printf("%-13s %9s %11s | %12s %12s | %10s %8s %8s %8s %9s %6s | %9s %s\n", "input", "vertices", "segments",
              "gDel2D ms", "its cons ms", "cdtgpu ms", "DT", "cons", "canon", "wall ms", "B/pt", "CGAL ms", "check");
  json out = json::array();
  int failures = 0;
  for (const Row& row : rows) {
    const E2eWorkload w = e2e_workload(row.points, row.segments, o.seed);
    const PreparedInput p = prepare(w.input);
    const std::string name =
        std::to_string(row.points / 1000) + "K" + (row.segments ? "+" + std::to_string(row.segments / 1000) + "K" : "");
    PeerTimes peer;
    if (!o.peer.empty()) {
      const std::string base = dir + "/" + name;
      write_gdel2d_input(p, base);
      ChildRun r = spawn_child({o.peer, "-inFile", base, "-r", std::to_string(o.runs + 1)}, {}, base + ".log", "",
                               dir);
      peer = parse_gdel2d(r.log);
      if (r.exit_code != 0 || peer.compute.size() != size_t(o.runs + 1))
        spdlog::error("{}: gDel2D exited {} with {} timed runs; its log: {}.log", name, r.exit_code,
                      peer.compute.size(), base);
      if (!peer.compute.empty()) {  // drop the warm-up
        peer.compute.erase(peer.compute.begin());
        peer.constraints.erase(peer.constraints.begin());
      }
    }
    OurTimes ours = time_ours(co, p, o.runs);
    std::string check = "-";
    std::vector<double> cgal_ms;
    if (p.vertices.size() <= o.cgal_max_points) {
      BackendRun cgal;
      for (int r = 0; r < cgal_runs; ++r) {
        cgal = run_cgal_fast(p);
        cgal_ms.push_back(cgal.total_ms);
      }
      canonicalize(cgal.mesh);
      const bool equal = cgal.mesh.triangles == ours.mesh.triangles;
      check = equal ? "gpu=cgal" : "FAIL";
      failures += !equal;
      if (!equal) spdlog::error("{}: the GPU's triangles differ from CGAL's", name);
    }
    const double bpt = p.vertices.empty() ? 0 : double(ours.peak_device_bytes) / double(p.vertices.size());
    std::printf("%-13s %9zu %11zu | %12s %12s | %10s %8s %8s %8s %9s %6.0f | %9s %s\n", name.c_str(),
                p.vertices.size(), p.constraints.size(), fmt(median(peer.compute)).c_str(),
                row.segments ? fmt(median(peer.constraints)).c_str() : "-", fmt(median(ours.gpu)).c_str(),
                fmt(median(ours.dt)).c_str(), fmt(median(ours.cdt)).c_str(), fmt(median(ours.canonical)).c_str(),
                fmt(median(ours.wall)).c_str(), bpt, fmt(median(cgal_ms)).c_str(), check.c_str());
    json stages = json::object();
    for (const auto& [k, v] : ours.stages) stages[k] = median(v);
    if (const char* e = std::getenv("CDTGPU_CDT_PROFILE_KERNELS"); e && std::string(e) == "1")
    {
      for (const auto& [k, v] : ours.stages) std::printf("    %-28s %8.3f ms\n", k.c_str(), median(v));
      std::printf("    insertion rounds (crossed edges, flips):");
      for (const auto& [found, flips] : ours.last.rounds) std::printf(" %u/%u", found, flips);
      std::printf("\n    legalise rounds (queued slots, flips):");
      for (const auto& [queued, flips] : ours.last.legalise_log) std::printf(" %u/%u", queued, flips);
      std::printf("\n");
    }
    std::fflush(stdout);
    out.push_back({{"input", name},
                   {"points", row.points},
                   {"segments", row.segments},
                   {"vertices", p.vertices.size()},
                   {"constraints", p.constraints.size()},
                   {"gdel2d_compute_ms", peer.compute},
                   {"gdel2d_constraints_ms", peer.constraints},
                   {"gpu_ms", ours.gpu},
                   {"gpu_dt_ms", ours.dt},
                   {"gpu_constraints_ms", ours.cdt},
                   {"gpu_canonical_ms", ours.canonical},
                   {"wall_ms", ours.wall},
                   {"gpu_stage_median_ms", stages},
                   {"peak_device_bytes", ours.peak_device_bytes},
                   {"cgal_ms", cgal_ms},
                   {"check", check}});
  }
  if (!o.json_path.empty()) {
    json j{{"tool", "cdtgpu bench --table peer"}, {"date", bench_utc_now()},  {"device", device},
           {"cpu", bench_cpu_model()},          {"peer", o.peer},             {"runs", o.runs},
           {"seed", o.seed},                    {"rows", out}};
    write_file_atomically(o.json_path, [&](std::ostream& f) { f << j.dump(2) << '\n'; });
  }
  return failures ? 1 : 0;
}

}  // namespace cdtgpu
