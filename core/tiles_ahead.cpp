#include "core/tiles_ahead.hpp"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace cdtgpu {

std::optional<Triangles> tiled_cdt_ahead(const PreparedInput& prepared, const ResolveProgress& progress,
                                         TileOptions options, const TileTriangulator& triangulate,
                                         TileStats* stats) {
  options.wait_clean = [&progress](double x) { return progress.wait_clean(x); };
  try {
    return tiled_cdt(prepared.vertices, prepared.constraints, options, triangulate, stats);
  } catch (const InputChangedByResolve&) {
    spdlog::debug("tiles begun before the resolve: it splits constraints, so they are tiled again from its result");
    return std::nullopt;
  }
}

void lower_this_thread_priority() {
  // Linux: PRIO_PROCESS with a thread id sets that thread's nice value alone. Best effort.
  if (setpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)), 10) != 0)
    spdlog::debug("the resolve's thread keeps its priority: setpriority failed");
}

}  // namespace cdtgpu
