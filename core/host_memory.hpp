// The machine's memory, as /proc/meminfo tells it: for the refusal of a run that cannot fit (cli/memory.hpp)
// and for work that holds more memory only where there is plenty (the tiles' output made ahead,
// core/tile_merge).
#pragma once
#include <cstdint>

namespace cdtgpu {

struct HostMemory {
  uint64_t total = 0;      // MemTotal of /proc/meminfo (0: unknown)
  uint64_t available = 0;  // MemAvailable
};
// The machine's memory; CDTGPU_HOST_MEMORY=BYTES stands for both (tests).
HostMemory host_memory();

}  // namespace cdtgpu
