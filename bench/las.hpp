// cdtgpu bench --table las: how fast LAS files are read (io/read_las.hpp), in process.
//
//   BenchOptions o;          // bench/bench.hpp
//   o.table = "las";
//   o.sizes = {"50M"};       // points per file (default 10M and 50M; --quick: 1M)
//   o.keep_dir = "/tmp/l";   // keep the files: `cdtgpu triangulate /tmp/l/points_f6.las ...` then times a whole run
//   int code = run_las(o);   // prints the table; 1 when a file reads back other points than were written
//
// Per size: the uniform workload (core/workloads.hpp, millimetre coordinates) written by tests/las_writer.hpp
// as LAS 1.2 point format 1 (28-byte records) and LAS 1.4 format 6 (30 bytes), every other point class 2; each
// file read once as a warm-up (so it is in the page cache: the figure is decoding, not the disk), then --runs
// times (median), keeping every point and keeping class 2 only. GB/s counts the file's point records.
#pragma once
#include "bench/bench.hpp"

namespace cdtgpu {

int run_las(const BenchOptions& options);

}  // namespace cdtgpu
