// cdtgpu batch JOBS: many triangulate runs in one process, one Vulkan device for all of them.
//
//   BatchOptions o;
//   o.jobs = "jobs.txt";          // one `cdtgpu triangulate` command line per line (cli/job_file.hpp); "-": stdin
//   o.stats_dir = "stats";        // each job's --stats JSON also as stats/<line>.json (optional)
//   o.defaults.backend = "gpu";   // for every line without --backend (and --device likewise)
//   int code = run_batch(o);      // 0: every job ran; 4: some failed (each named on stderr); 2: no job file
//
// The jobs run through the stages of cli/stages.hpp on three threads, in file order: job k+1 is read and
// prepared while job k is triangulated (regions, grid, contours: the device's stages, one job at a time) and
// job k-1 is written. At most three jobs are held at once. A job that reads a file an earlier job writes waits
// for that write. A failing job (bad line, bad input, a device failure) is logged with its line number and
// writes nothing; the others run. Each job's outputs are the bytes its own `cdtgpu triangulate` writes.
#pragma once
#include <string>

#include "cli/options.hpp"

namespace cdtgpu {

struct BatchOptions {
  std::string jobs;
  std::string stats_dir;  // empty: none
  JobDefaults defaults;
};

// The exit code when some job failed (the others ran): the usual 2 and 3 mean the batch itself did not run.
constexpr int kSomeJobsFailed = 4;

int run_batch(const BatchOptions& options);

}  // namespace cdtgpu
