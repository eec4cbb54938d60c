// Each tile's segments for core/tiles: every segment goes to every tile whose closed rectangle it meets
// (whole, with its endpoints), each tile's list in segment order.
//
//   TileSegments ts = tile_segments(vertices, segments, plan);   // segments sorted, as the tiles take them
//   RawVector<uint32_t> scratch;
//   std::span<const uint32_t> mine = ts.of(t, scratch);          // tile t's segment ids
#pragma once
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "core/tile_plan.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {

struct TileSegments {
  // Squares: tile t's ids are ids[first[t], first[t + 1]).
  RawVector<uint32_t> ids;
  std::vector<size_t> first;
  // Slabs: tile t's are the range of segments whose first end it owns (segments are sorted by it, and a
  // slab's vertices are a range of ids), and the few of other ranges that meet it (extra[t], in order).
  std::vector<std::pair<uint32_t, uint32_t>> range;
  std::vector<std::vector<uint32_t>> extra;

  // Tile t's segment ids in order: in `ids`, or written into `scratch` for a slab.
  std::span<const uint32_t> of(size_t t, RawVector<uint32_t>& scratch) const;
};

// `segments` (a < b) sorted (the merge input relies on it too) and `plan` made over `vertices` (sorted by
// (x, y)); a logic_error where the segments are not.
TileSegments tile_segments(const Points& vertices, const std::vector<Edge>& segments, const TilePlan& plan);

}  // namespace cdtgpu
