// cdtgpu bench --table e2e: the whole `cdtgpu triangulate` as a user runs it, timed from the outside.
//
//   BenchOptions o;                      // bench/bench.hpp
//   o.table = "e2e";
//   o.sizes = {"20K"};                   // points; each row gets a quarter as many contour segments
//   o.backends = {"cgal", "gpu"};        // the child's --backend values (default auto, gpu, cgal, batch)
//   o.binary = "build/cdtgpu";           // default: this executable
//   int code = run_e2e(o);               // prints the table; 1 when outputs differ or a run failed
//
// Per row: the inputs are written once (bench/e2e_workload.hpp), as text (.xyz + .wkt) and as shapefiles;
// per format and backend the child `cdtgpu triangulate INPUTS -o OUT.ply --stats S.json -q --backend B` runs
// once with empty caches (the first-run figure: XDG_CACHE_HOME, __GL_SHADER_DISK_CACHE_PATH and
// MESA_SHADER_CACHE_DIR point at fresh empty folders), once as a warm-up, then --runs times; the wall clock
// is spawn to waitpid, and each run's stats JSON gives its stages. Every PLY written in a row must be
// byte-identical to the row's first. Backend "batch": the child is `cdtgpu batch JOBS -q`, JOBS holding
// --batch-jobs copies of the run (`--backend auto`, each its own PLY and stats); its wall is spawn to exit
// divided by the jobs, its stages the last job's, and every job's PLY must equal the row's first too.
#pragma once
#include "bench/bench.hpp"

namespace cdtgpu {

int run_e2e(const BenchOptions& options);

}  // namespace cdtgpu
