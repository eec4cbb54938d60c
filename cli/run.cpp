#include "cli/run.hpp"

#include <algorithm>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "cli/stages.hpp"
#include "core/regions.hpp"
#include "core/verify.hpp"
#include "core/verify_regions.hpp"
#include "io/tiles_dir.hpp"

namespace cdtgpu {

int run_triangulate(const TriangulateOptions& options) {
  Job job;
  job.options = options;
  GpuStarts gpus;
  check_job(job);
  start_gpu_early(job, gpus);
  // Under MPI the other ranks read their shares for rank 0 and run the tiles it hands them; rank 0 finishes and
  // writes. They write only their share of --tiles-out's files, which rank 0 hands them.
  if (options.ranks && options.ranks->rank != 0) {
    serve_tiles(job);
    // Its device closed now, while rank 0 writes: left to the exit, the teardown (its pool and staging) came
    // after rank 0's, and mpirun ended ~0.3 s after rank 0 on the 2 x H200 host.
    gpus.close_in_background();
    release_job(job, &gpus);
    if (options.tiles_sharing && !options.tiles_out.empty()) write_shared_tiles(job.write, *options.tiles_sharing);
    return 0;
  }
  read_job(job);
  choose_backend(job, gpus);
  open_tiles_early(job);
  prepare_job(job, true);
  triangulate_job(job);
  if (options.ranks) {
    const uint64_t elsewhere = options.ranks->end();
    job.stats.counts["tiles_at_other_ranks"] = elsewhere;
    if (elsewhere) spdlog::info("{} of the tiles ran at the other {} rank(s)", elsewhere, options.ranks->ranks - 1);
  }
  apply_job_regions(job);
  derive_and_write_outputs(job, [&] { gpus.close_in_background(); });
  count_results(job);
  release_job(job, &gpus);
  write_job_stats(job);
  return 0;
}

int run_verify(const std::string& mesh_path, const InputOptions& options, double max_edge) {
  // A --tiles-out folder: the union of its files, each triangle in exactly one (checked), verified as one mesh.
  Mesh mesh = std::filesystem::is_directory(mesh_path) ? read_tiles_dir(mesh_path) : read_mesh_file(mesh_path);
  Job job;
  job.options.input = options;
  read_job(job);
  prepare_job(job);
  const RegionRules rules = region_rules(job.in, job.parts, job.prepared, max_edge);
  const bool regions = std::count(rules.region_edge.begin(), rules.region_edge.end(), 1) > 0 || max_edge > 0;
  VerifyReport report = regions ? verify_regions(mesh, job.prepared, rules) : verify_mesh(mesh, job.prepared);
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
