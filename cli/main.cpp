// cdtgpu command line: parses options and calls cli/run.cpp or cli/batch.cpp. Exit codes: 0 ok, 1 verify failed,
// 2 bad input or usage, 3 any other failure (GPU, out of memory, internal), 4 batch: some jobs failed.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

#include "bench/bench.hpp"
#include "cli/batch.hpp"
#include "cli/job_log.hpp"
#include "cli/mpi.hpp"
#include "cli/options.hpp"
#include "cli/run.hpp"
#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "gpu/devices.hpp"
#include "core/error.hpp"

using namespace cdtgpu;

namespace {

int run_cli(int argc, char** argv, const MpiSession& mpi) {
  auto logger = spdlog::stderr_color_mt("cdtgpu");
  use_job_log(*logger);  // "cdtgpu: LEVEL: MESSAGE", a batch's job named before the message
  spdlog::set_default_logger(logger);
  spdlog::set_level(spdlog::level::info);
  if (mpi.ranks() > 1)  // every line names its rank and host
    logger->set_pattern("cdtgpu rank " + std::to_string(mpi.rank()) + " of " + std::to_string(mpi.ranks()) +
                        " on " + mpi.host() + ": %l: %v");
  if (!mpi.refusal().empty()) {
    spdlog::error("{}", mpi.refusal());
    return 2;
  }
  if (!mpi.cpu_note().empty()) spdlog::warn("{}", mpi.cpu_note());

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

  TriangulateArgs tri;
  auto* t = app.add_subcommand("triangulate", "triangulate inputs into a TIN");
  add_triangulate_options(t, tri);

  std::string mesh_path;
  InputOptions ver;
  auto* v = app.add_subcommand("verify", "check a mesh is the constrained Delaunay triangulation of the inputs");
  v->add_option("mesh", mesh_path, "mesh written by cdtgpu triangulate, or a --tiles-out folder")->required();
  v->add_option("inputs", ver.inputs, "the inputs it was made from, with the same options")->required();
  CrsArgs ver_crs;
  add_input_options(v, ver, ver_crs);
  double verify_max_edge = 0;
  add_verify_options(v, verify_max_edge);

  BatchOptions batch;
  auto* j = app.add_subcommand("batch", "run many triangulate jobs, one per line of a file, in one process");
  j->add_option("jobs", batch.jobs,
                "file with one job a line: the arguments of `cdtgpu triangulate` (shell quoting, # comments), "
                "or - for stdin")
      ->required();
  j->add_option("--stats-dir", batch.stats_dir, "also write each job's stats JSON as DIR/LINE.json");
  j->add_option("--backend", batch.defaults.backend, "auto, gpu or cgal for every job whose line has no --backend")
      ->check(CLI::IsMember({"auto", "gpu", "cgal"}));
  j->add_option("--devices", batch.devices,
                "GPUs that run the jobs' device stages, a worker each: all, or indices as `cdtgpu devices` lists "
                "them (an index twice: two workers there); default: one, the device --device or a single run picks");

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
  if (mpi.ranks() > 1) spdlog::debug("MPI_Init_thread: {:.1f} ms", mpi.init_ms());
  // Rank 0 tells the story; with -v every rank does, each line naming its rank.
  if (quiet || (mpi.rank() != 0 && !verbose)) spdlog::set_level(spdlog::level::warn);
  if (mpi.ranks() > 1 && !*t) {
    spdlog::error("only `cdtgpu triangulate` runs as several MPI processes");
    return 2;
  }

  try {
    if (*t) {
      TriangulateOptions options = triangulate_options(tri);
      options.device = device;
      options.ranks = mpi.rank_tiles();
      options.input.read.share = mpi.read_share();
      options.tiles_sharing = mpi.tiles_dir();
      options.devices_shared = mpi.ranks() > 1;
      // Ranks of one host take a GPU each (their local rank's), unless --device or --devices says otherwise.
      if (mpi.ranks() > 1 && options.backend != "cgal" && options.device.empty() && options.devices.empty()) {
        options.rank_gpu = mpi.local_rank();
        options.host_ranks = mpi.local_ranks();
        options.devices_shared = false;  // the device's start finds out (gpu::Context::shared)
      }
      return run_triangulate(options);
    }
    if (*v) {
      ver.crs = crs_from(ver_crs);
      return run_verify(mesh_path, ver, verify_max_edge);
    }
    if (*j) {
      batch.defaults.device = device;
      if (!device.empty() && !batch.devices.empty()) {
        spdlog::error("batch: --device names the one device for every job; --devices, its workers: not both");
        return 2;
      }
      return run_batch(batch);
    }
    if (*b) {
      bench.device = device;
      return run_bench(bench);
    }
    if (*d) {
      std::cout << gpu::describe_devices(device);
      // What a tiled GPU run spreads over without --devices (cli/stages.cpp, tile_devices).
      std::string tiled;
      for (size_t i : gpu::select_devices(gpu::list_devices(), "all")) tiled += (tiled.empty() ? "" : ", ") + std::to_string(i);
      std::cout << "Tiled GPU runs use device(s) " << tiled << " (--devices all, the default; --devices 0,2 picks)\n";
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

}  // namespace

int main(int argc, char** argv) {
  MpiSession mpi(&argc, &argv);
  const int code = run_cli(argc, argv, mpi);
  // The other ranks may be waiting for this one, unless they are done.
  if (code != 0 && mpi.ranks() > 1 && !mpi.others_done()) mpi.abort(code);
  return code;
}
