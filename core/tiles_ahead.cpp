#include "core/tiles_ahead.hpp"

#include <spdlog/spdlog.h>

namespace cdtgpu {

std::optional<Triangles> tiled_cdt_unresolved(const PreparedInput& prepared, TileOptions options,
                                              const TileTriangulator& triangulate, TileStats* stats) {
  options.unresolved = true;
  try {
    return tiled_cdt(prepared.vertices, prepared.constraints, options, triangulate, stats);
  } catch (const UnresolvedTile& e) {
    spdlog::debug("the input has constraints to split ({}): resolved, then tiled again", e.what());
    return std::nullopt;
  }
}

}  // namespace cdtgpu
