#include "core/host_memory.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace cdtgpu {

HostMemory host_memory() {
  HostMemory m;
  if (const char* v = std::getenv("CDTGPU_HOST_MEMORY"); v && *v) {
    m.total = m.available = std::strtoull(v, nullptr, 10);
    return m;
  }
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);) {
    std::istringstream s(line);
    std::string key;
    uint64_t kib = 0;
    s >> key >> kib;
    if (key == "MemTotal:") m.total = kib * 1024;
    if (key == "MemAvailable:") m.available = kib * 1024;
  }
  return m;
}

}  // namespace cdtgpu
