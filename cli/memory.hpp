// Host memory: what a run will need, what the machine has, and the refusal of a run that cannot fit, before
// it reads (from the files' sizes) and again once the points are read. A run that does not fit would otherwise
// be killed by the kernel's out-of-memory killer after minutes of work, or page for hours.
//
//   check_host_memory(estimate_input_points(paths), kHostBytesPerPoint, "estimated from the input files");
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

namespace cdtgpu {

// Resident bytes a `cdtgpu triangulate` run holds at its peak per input vertex, the largest measured (H100
// machine, 16M points + 4M segments, 20M input vertices, 2026-11-27, since the input is dropped after prepare):
// GPU 158, GPU tiles 179, CGAL tiles 190, GPU --max-edge 20 158; boundaries and holes keep their rings, and were
// 237 before (docs/performance.md, "Host memory").
constexpr uint64_t kHostBytesPerPoint = 205;
constexpr uint64_t kHostBytesPerPointRegions = 240;

struct HostMemory {
  uint64_t total = 0;      // MemTotal of /proc/meminfo (0: unknown)
  uint64_t available = 0;  // MemAvailable
};
// The machine's memory; CDTGPU_HOST_MEMORY=BYTES stands for both (tests).
HostMemory host_memory();

// A run the machine's memory cannot hold: exit code 3, before the work.
struct HostMemoryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Throws HostMemoryError when `points` vertices need more than the machine's memory; warns when they need more
// than is available now (other processes hold the rest). `what`: where the count comes from, for the message.
void check_host_memory(uint64_t points, uint64_t bytes_per_point, const std::string& what);

// The process's peak resident bytes so far (getrusage).
uint64_t peak_host_bytes();

}  // namespace cdtgpu
