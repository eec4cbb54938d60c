#include "core/tiles_ahead.hpp"

#include <spdlog/spdlog.h>

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

}  // namespace cdtgpu
