#include "core/tiles_ahead.hpp"

#include <spdlog/spdlog.h>

#include "core/resolve.hpp"

namespace cdtgpu {

std::optional<OrderedRuns> tiled_cdt_unresolved(const PreparedInput& prepared, TileOptions options,
                                              const TileTriangulator& triangulate, TileStats* stats) {
  options.unresolved = true;
  try {
    return tiled_cdt_runs(prepared.vertices, prepared.constraints, options, triangulate, stats);
  } catch (const UnresolvedTile& e) {
    spdlog::debug("the input has constraints to split ({}): resolved, then tiled again", e.what());
    return std::nullopt;
  }
}

CdtResult triangulate_tiled_checking(const PreparedInput& prepared, const TileOptions& options,
                                     const TileTriangulator& triangulate, TileStats* stats) {
  std::optional<OrderedRuns> t = tiled_cdt_unresolved(prepared, options, triangulate, stats);
  if (!t) return triangulate_tiled(resolve_constraints(prepared), options, triangulate, stats);
  CdtResult r;
  r.mesh.vertices = prepared.vertices;  // unchanged: the tiles split segments at them, and nothing crosses
  if (options.in_runs)
    r.in_runs = std::move(*t);
  else
    r.mesh.triangles = std::move(*t).take();
  return r;
}

}  // namespace cdtgpu
