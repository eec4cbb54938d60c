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

std::optional<Triangles> tiled_cdt_unresolved(const PreparedInput& prepared, TileOptions options,
                                              const TileTriangulator& triangulate, TileStats* stats) {
  options.unresolved = true;
  options.wait_clean = nullptr;
  try {
    return tiled_cdt(prepared.vertices, prepared.constraints, options, triangulate, stats);
  } catch (const UnresolvedTile& e) {
    spdlog::debug("the input has constraints to split ({}): resolved, then tiled again", e.what());
    return std::nullopt;
  }
}

}  // namespace cdtgpu
