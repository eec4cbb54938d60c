// Tiles begun at once, before any resolve: the GPU's tiles of a large input need their segments resolved (no
// crossings, no vertex inside one), and at 1B points + 250M segments the resolve took 7-9 s on 32 cores while the
// devices waited. Nearly every real input (contours, breaklines, footprints) has nothing to split, so each tile
// checks its own segments on the device instead, and the resolve runs only when one has something. That input is
// then tiled again from its resolved input: the same bytes. Segments through vertices (contours through LiDAR
// points, footprints sharing walls) are no such thing: the tiles split them (TileOptions::unresolved).
//
//   std::optional<OrderedRuns> t = tiled_cdt_unresolved(prepared, options, triangulate, &stats);
//   if (!t) t = OrderedRuns(triangulate_tiled(resolve_constraints(prepared), options, triangulate, &stats).mesh.triangles);
//
// or, with a copy of the prepared vertices, triangulate_tiled_checking(prepared, options, triangulate).
#pragma once
#include <optional>

#include "core/prepare.hpp"
#include "core/tiles.hpp"

namespace cdtgpu {

// tiled_cdt of the prepared input with no resolve at all: a finalizer that checks its tiles (the GPU's,
// TileOptions::unresolved) finds what the resolve would split in the first level's tiles. The triangles
// (canonical; one array, or left in the tiles' runs where options.in_runs says so) when no two segments cross: the resolve would only split segments at vertices, and the tiles did
// (stats->split_at_vertices counts them). nullopt when some cross (the tiles in flight finish first, the rest
// are not begun); the caller resolves and tiles again.
std::optional<OrderedRuns> tiled_cdt_unresolved(const PreparedInput& prepared, TileOptions options,
                                              const TileTriangulator& triangulate, TileStats* stats = nullptr);

// The mesh as cdtgpu triangulate makes it in GPU tiles: tiled_cdt_unresolved, else resolved and tiled again. The
// prepared vertices are copied (the CLI moves its own instead).
CdtResult triangulate_tiled_checking(const PreparedInput& prepared, const TileOptions& options,
                                     const TileTriangulator& triangulate, TileStats* stats = nullptr);

}  // namespace cdtgpu
