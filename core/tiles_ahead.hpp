// Tiles begun before the resolve ends: the GPU's tiles of a large input need their segments resolved (no
// crossings, no vertex inside one), and at 1B points + 250M segments the resolve took 4-6 s on all cores
// while the devices waited. The resolve's first sweep goes over the input in x order, roughly, and tells which
// x it has cleared (ResolveProgress); a tile of the prepared input starts once everything up to its largest x
// is, and the merge once all is. Nearly every real input (contours, breaklines, footprints) has nothing to
// split: its tiles are the run's. One that has is tiled again from its resolved input: the same bytes.
//
//   ResolveProgress progress;
//   auto resolving = std::async(std::launch::async, [&] { return resolve_if_needed(prepared, progress); });
//   std::optional<Triangles> t = tiled_cdt_ahead(prepared, progress, options, triangulate, &stats);
//   ResolvedInput in = resolving.get();  // t: in.unchanged, and t is the mesh of prepared.vertices
#pragma once
#include <optional>

#include "core/resolve.hpp"
#include "core/tiles.hpp"

namespace cdtgpu {

// tiled_cdt of the prepared input while its resolve runs elsewhere, reporting to `progress`: its triangles
// (canonical) when the resolve found nothing to split, nullopt as soon as it found something (the tiles done
// so far are dropped). `options.wait_clean` is set here.
std::optional<Triangles> tiled_cdt_ahead(const PreparedInput& prepared, const ResolveProgress& progress,
                                         TileOptions options, const TileTriangulator& triangulate,
                                         TileStats* stats = nullptr);

// tiled_cdt of the prepared input with no resolve at all: a finalizer that checks its tiles (the GPU's,
// TileOptions::unresolved) finds what the resolve would split in the first level's tiles. The triangles
// (canonical) when no tile has any: the input is its own resolved input, unchanged. nullopt when one has (the
// tiles in flight finish first, the rest are not begun); the caller resolves and tiles again. At 1B points +
// 250M segments on 32 cores the resolve's sweep took 7-9 s beside the tiles, and each tile waited for it.
std::optional<Triangles> tiled_cdt_unresolved(const PreparedInput& prepared, TileOptions options,
                                              const TileTriangulator& triangulate, TileStats* stats = nullptr);

}  // namespace cdtgpu
