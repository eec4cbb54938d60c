// plan_tiles: k-d tiles of at most max_points vertices each, for core/tiles. Columns of equal counts, each cut
// into cells of equal counts, as a binary tree over the cuts; or slabs, one tile a column.
//
//   Plan plan = plan_tiles(vertices, 1 << 20);  // vertices sorted by (x, y), as the resolve leaves them
//   for (uint32_t t : plan.tiles) {
//     const TileNode& node = plan.nodes[t];  // its rectangle, its ids plan.id_at(node.lo .. node.hi - 1)
//   }
#pragma once
#include <cstdint>
#include <vector>

#include "core/tiles.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {

// A tile's closed rectangle (TileRect) is ±inf on the outside of the data. Its vertices may lie on its border
// (shared with a neighbour, each vertex in one of them); every vertex strictly inside it is one of its own.
struct TileNode {
  TileRect rect;
  uint32_t lo = 0, hi = 0;                // its own vertices: plan.id_at(lo .. hi - 1)
  int32_t left = -1, right = -1;          // children; -1: a tile
  uint32_t column_lo = 0, column_hi = 0;  // a tile: the ids of its column, which hold its own
};

struct TilePlan {
  RawVector<uint32_t> order;      // vertex ids, each node's a contiguous range; empty for slabs (order[i] = i)
  std::vector<TileNode> nodes;    // nodes[0]: the root
  std::vector<uint32_t> tiles;    // the leaf nodes, left to right in the tree
  bool slabs = false;             // one tile a column
  uint32_t id_at(uint32_t i) const { return slabs ? i : order[i]; }  // the vertex at place i of the order
};

// TileShape: about square tiles (the shortest border, so the smallest merge), or slabs: columns of the (x, y)
// order, which need no selection, each tile a range of ids. `automatic`: slabs for tiles of 2^24 points or more
// (a GPU's) unless they would be over 64 times as tall as wide (auto_slabs), else squares.
// ramp (slabs only; 0 or 1: none): the first and the last slab each cut into `ramp` thinner ones, so that the
// devices start on small tiles (each device's first waits for the plan and the tiles gathered before it) and
// end on small ones (the last tile's copies and bookkeeping come before the merge).
TilePlan plan_tiles(const Points& v, uint64_t max_points, TileShape shape = TileShape::squares, unsigned ramp = 0);

// The automatic shape: slabs for `tiles` tiles of at most max_points points over an input w wide and h tall? Up to
// 64 times as tall as wide, since 32 slabs of 39M points beat 35 squares at 1B points + 250M contour vertices on
// two H200s (whole runs 17.7 against 34.3 s: the squares' selections took 4.0 s of the plan, slabs' 54 ms; their
// merge 10.7M vertices against 3.8M; docs/tiles.md, session 64). The limit was 16 until then.
bool auto_slabs(uint64_t tiles, uint64_t max_points, double w, double h);

}  // namespace cdtgpu
