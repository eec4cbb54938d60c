// The stages of one `cdtgpu triangulate` run, each a function of the Job (cli/job.hpp) that fills in what it
// made. run_triangulate (cli/run.cpp) calls them in a row; cdtgpu batch (cli/batch.cpp) calls the same ones on
// three threads, so that reading one job and writing another overlap the triangulation of a third.
//
//   Job job{options};
//   GpuStarts gpus;                 // one Vulkan device for every job of the process
//   check_job(job);                 // usage errors before anything is read
//   start_gpu_early(job, gpus);     // large files: the device starts while they are read
//   read_job(job);                  // read, project, drape
//   choose_backend(job, gpus);      // auto: by the points read
//   prepare_job(job, true);         // duplicates merged, segments indexed; a single run begins the mesh
//                                   // file there (begin_mesh_file): its vertices written from then on
//   triangulate_job(job);           // CGAL, the GPU, or tiles of either        } the device's stages: one
//   apply_job_regions(job);         // boundaries, holes, --max-edge            } job at a time in a batch
//   derive_outputs(job);            // grid, contours, preview's raster         }
//   write_outputs(job);             // mesh, tiles, grid, contours, preview (a single run: the mesh while
//                                   // the derived outputs are made, derive_and_write_outputs)
//   count_results(job);             // the last counts into job.stats
//   release_job(job);
//   write_job_stats(job);           // --stats
//
// Every stage times itself into job.stats.stage_ms under the name the stats have always used. Bad input throws
// InputError / UsageError, a device that fails a forced GPU run throws gpu::DeviceError; auto falls back to the
// CPU with the same bytes.
#pragma once
#include <functional>

#include "cli/gpu_start.hpp"
#include "cli/job.hpp"

namespace cdtgpu {

void check_job(Job& job);
void start_gpu_early(Job& job, GpuStarts& gpus);
void read_job(Job& job);
// The host memory the job may hold at its peak, from the files' sizes (cli/memory.hpp's bytes a point).
uint64_t estimated_peak_bytes(Job& job);
void choose_backend(Job& job, GpuStarts& gpus);
// The start a job's device stages take on another device (a batch's device worker, cli/batch_devices): asked for
// with the job's own rule and size from its files, started now if it was not. `copy`: GpuStarts::start's.
GpuStart& gpu_start_on(Job& job, GpuStarts& gpus, const std::string& device, unsigned copy);
// A large GPU run's tile devices and their staging, begun before prepare (not in a batch).
void open_tiles_early(Job& job);
// mesh_file_ahead (a single run): begin_mesh_file as soon as the vertices are merged, before prepare makes,
// sorts and checks the segments (0.25-0.3 s at 100M points + 25M contour vertices on the 2 x H200 host, ~1.6 s
// at 1B + 250M): where the whole output keeps the disk busy, the run ends that much sooner (5850 -> 5382 ms at
// 100M there, medians of five).
void prepare_job(Job& job, bool mesh_file_ahead = false);
// An MPI rank other than 0 (cli/mpi.hpp): reads its share for rank 0, then runs the tiles rank 0 hands it.
void serve_tiles(Job& job);
// A batch's GPU job in one piece: its constraints resolved now, in the reader's stage, beside the device stages of
// the jobs before it (a single run resolves beside the device's start and Delaunay build instead, and
// triangulate_job takes either). Nothing for a CPU job or a tiled one (whose tiles check themselves).
void resolve_early(Job& job);
// The output's vertex section written on a thread of its own from the prepared vertices (io/mesh_file_ahead),
// where they will be the mesh's: OBJ and PLY files of a run without boundaries, holes or --max-edge. The
// write stage adds the faces, or writes the whole file where the run added vertices (crossings). Not in a batch,
// whose writer is busy with the job before. `vertices`: prepare's, which become job.prepared.vertices.
void begin_mesh_file(Job& job, const Points& vertices);
void triangulate_job(Job& job);
void apply_job_regions(Job& job);
void derive_outputs(Job& job);
void write_outputs(Job& job);
// A single run's derive_outputs + write_outputs, the mesh written on a thread of its own meanwhile.
// `device_done` is called once the device has no more work (before the writing, or beside it).
void derive_and_write_outputs(Job& job, const std::function<void()>& device_done = {});
void count_results(Job& job);
// Frees the job's data (timed as "release"); `exiting`: the process ends after this job, so the GPU's
// pipelines are saved and the device is left to the operating system (GpuStart::leave_for_exit).
void release_job(Job& job, GpuStarts* exiting = nullptr);
void write_job_stats(const Job& job);

}  // namespace cdtgpu
