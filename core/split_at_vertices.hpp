// What the resolve makes of segments that pass through vertices but never cross, from what tiles found: the
// tiles of an unresolved input (core/tiles.hpp, TileOptions::unresolved) split the segments they hold at
// their own vertices, and the merge needs the whole input's segments split the same way.
//
//   VertexSplits s = split_at_vertices(vertices, segments, found);  // found: every tile's (a, b, v)
//   // segments, the split ones replaced by s.pieces, sorted and unique: the resolve's constraints for an input
//   // without crossings (tests/split_at_vertices_test)
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

struct VertexSplits {
  std::vector<Edge> split;   // the segments split, sorted
  std::vector<Edge> pieces;  // their pieces, sorted, unique (one may equal a segment not split)
  uint64_t splits = 0;       // ResolvedInput::split_at_vertices
};

// `vertices` sorted by (x, y); `segments` (a < b) sorted, unique; `found` holds (a, b, v): a segment or a
// piece of one, and a vertex exactly inside it. Each segment that has a vertex inside it must be in `found`
// as itself, and each such vertex must be a v of `found` (for any segment): a tile's first pass reports each
// of its segments through a vertex at once, and its later passes report the rest on the pieces. Each of those
// segments is split at every v of `found` inside it (exactly: orient2d). Cost: the found ones' alone, not the
// segments' (the merge of tiles takes only the few of them it needs).
VertexSplits split_at_vertices(const Points& vertices, const std::vector<Edge>& segments,
                               std::vector<std::array<uint32_t, 3>> found);

}  // namespace cdtgpu
