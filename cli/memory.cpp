#include "cli/memory.hpp"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace cdtgpu {

namespace {

std::string gigabytes(uint64_t bytes) {
  char buf[32];
  if (bytes >= 1000000000)
    std::snprintf(buf, sizeof buf, "%.1f GB", double(bytes) / 1e9);
  else
    std::snprintf(buf, sizeof buf, "%.1f MB", double(bytes) / 1e6);
  return buf;
}

}  // namespace

uint64_t host_bytes_per_point_cpu(uint64_t points, uint64_t in_flight_points) {
  if (!points) return 85;
  return 85 + (230 * std::min(points, in_flight_points) + points - 1) / points;
}

void check_host_memory(uint64_t points, uint64_t bytes_per_point, const std::string& what) {
  const HostMemory m = host_memory();
  if (!m.total || !points) return;
  const uint64_t need = points * bytes_per_point;
  const std::string about = std::to_string(points) + " input points (" + what + ") need about " + gigabytes(need) +
                            " of memory (" + std::to_string(bytes_per_point) + " bytes a point)";
  if (need > m.total)
    throw HostMemoryError(about + "; this machine has " + gigabytes(m.total) +
                          ": split the input (by area, into several runs) or use a machine with more memory");
  // What this process holds already (the points read, at the second check) is part of the need and no longer
  // free: counted once.
  const uint64_t held = resident_bytes();
  if (need > m.available + held)
    spdlog::warn("{}; {} of this machine's {} are free now: the run may page or be killed", about,
                 gigabytes(m.available + held), gigabytes(m.total));
}

uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t pages = 0, resident = 0;
  if (!(statm >> pages >> resident)) return 0;
  return resident * uint64_t(sysconf(_SC_PAGESIZE));
}

uint64_t peak_host_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return uint64_t(u.ru_maxrss) * 1024;  // KiB on Linux
}

}  // namespace cdtgpu
