// cdtgpu batch JOBS: many triangulate runs in one process, a Vulkan device a worker for all of them.
//
//   BatchOptions o;
//   o.jobs = "jobs.txt";          // one `cdtgpu triangulate` command line per line (cli/job_file.hpp); "-": stdin
//   o.stats_dir = "stats";        // each job's --stats JSON also as stats/<line>.json (optional)
//   o.defaults.backend = "gpu";   // for every line without --backend (and --device likewise)
//   o.devices = "0,1";            // device workers (cli/batch_devices); default: one, on a single run's device
//   int code = run_batch(o);      // 0: every job ran; 4: some failed (each named on stderr); 2: no job file
//
// The jobs run through the stages of cli/stages.hpp: job k+1 is read and prepared while the device workers run
// the device stages (triangulate, regions, grid, contours) of the jobs before it, each taking the next job as it
// becomes free, and as many writers write the jobs done (in any order; each job's summary line when it is
// written). A worker runs one job at a time on its GPU; a job that names its own --device runs there. At most one
// job more than twice the workers is held at once. A job that reads a file an earlier job writes waits for
// that write (and for every job before it). A failing job (bad line, bad input, a
// device failure) is logged with its line number and writes nothing; the others run. Each job's outputs are the
// bytes its own `cdtgpu triangulate` writes, on whichever device.
#pragma once
#include <string>

#include "cli/options.hpp"

namespace cdtgpu {

struct BatchOptions {
  std::string jobs;
  std::string stats_dir;  // empty: none
  JobDefaults defaults;
  std::string devices;  // --devices: "all", or indices ("0,0": two workers on GPU 0); empty: one worker
};

// The exit code when some job failed (the others ran): the usual 2 and 3 mean the batch itself did not run.
constexpr int kSomeJobsFailed = 4;

int run_batch(const BatchOptions& options);

}  // namespace cdtgpu
