// Each tile's segments for core/tiles: every segment goes to every tile whose closed rectangle it meets
// (whole, with its endpoints), each tile's list in segment order.
//
//   TileSegments ts = tile_segments(vertices, segments, plan);   // segments sorted, as the tiles take them
//   RawVector<uint32_t> scratch;
//   std::span<const uint32_t> mine = ts.of(t, scratch);          // tile t's segment ids
#pragma once
#include <cstdint>
#include <memory>
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
  // slab's vertices are a range of ids), and the few of other ranges that meet it, in order. Those are found
  // on a thread of their own, range by range from the left: a slab's list is whole once the ranges up to the
  // next slab of some width are scanned, so the first tiles need not wait for the pass over all segments
  // (~150 ms at 1B points on 64 cores).
  std::vector<std::pair<uint32_t, uint32_t>> range;
  struct Extras;
  std::shared_ptr<Extras> extras;

  // Tile t's segment ids in order: in `ids`, or written into `scratch` for a slab (waiting for its extras).
  std::span<const uint32_t> of(size_t t, RawVector<uint32_t>& scratch) const;
  // Slabs: how many ranges, from the left, of() waits to have scanned for tile t.
  size_t waits_for(size_t t) const;
};

// `segments` (a < b) sorted (the merge input relies on it too) and `plan` made over `vertices` (sorted by
// (x, y)); a logic_error where the segments are not (from of(), for slabs). All three must outlive the result.
TileSegments tile_segments(const Points& vertices, const std::vector<Edge>& segments, const TilePlan& plan);

}  // namespace cdtgpu
