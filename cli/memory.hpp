// Host memory: what a run will need, what the machine has, and the refusal of a run that cannot fit, before
// it reads (from the files' sizes) and again once the points are read. A run that does not fit would otherwise
// be killed by the kernel's out-of-memory killer after minutes of work, or page for hours.
//
//   check_host_memory(estimate_input_points(paths), kHostBytesPerPointGpu, "estimated from the input files");
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/host_memory.hpp"

namespace cdtgpu {

// Resident bytes a `cdtgpu triangulate` run holds at its peak per input vertex, at least as many as measured
// (H100 machine, text points + contour lines, 2026-11-27, session 40; docs/performance.md, "Host memory"). The
// GPU backend in tiles: 146 at 20M input vertices, 91 at 80M, 72 at 200M, 70 at 1.25B (fixed costs such as the
// device's staging spread thinner; the slope is ~60), so 95 holds where the input is beyond any device's tile
// and the machine's memory matters. The GPU in one piece (up to ~200M points): 126 at 20M, 103 at 80M, so 130.
// The CPU backend: see host_bytes_per_point_cpu. Boundaries, holes and --max-edge keep the prepared input to the
// end (24 bytes a vertex and 12 a segment) and their own tables: 40 more.
constexpr uint64_t kHostBytesPerPointGpuTiles = 95;
constexpr uint64_t kHostBytesPerPointGpu = 130;
constexpr uint64_t kHostBytesPerPointRegions = 40;  // added to any

// The CPU backend (CGAL): 85 bytes a point for the input, its resolved copy and the tiles' final triangles, and
// 230 more for each point in CGAL's structures at once: the tiles in flight (cores x tile), or the whole input
// in one piece. Measured at 20M input vertices (session 41, 2 cores): tiles of 1M 79.5 bytes a point (this gives
// 108), tiles of 2.5M 111 (143), one CGAL run 305 (315); on 16 threads, a quarter in flight, 135 (143; session
// 40). It was 140 for all: one CGAL run (one core, --max-tile-points 0) needs twice that.
uint64_t host_bytes_per_point_cpu(uint64_t points, uint64_t in_flight_points);

// A run the machine's memory cannot hold: exit code 3, before the work.
struct HostMemoryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Throws HostMemoryError when `points` vertices need more than the machine's memory; warns when they need more
// than is available now (other processes hold the rest). `what`: where the count comes from, for the message.
void check_host_memory(uint64_t points, uint64_t bytes_per_point, const std::string& what);

// The process's resident bytes now (/proc/self/statm; 0 where unknown).
uint64_t resident_bytes();

// The process's peak resident bytes so far (getrusage).
uint64_t peak_host_bytes();

}  // namespace cdtgpu
