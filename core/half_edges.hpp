// Twins of the half-edges of a triangle list in canonical order (each triangle from its smallest vertex, the
// list sorted), found from that order on all cores: only edges whose two triangles both start elsewhere are
// paired by a sort. Half-edge h = 3 t + k runs from triangle t's vertex k to vertex k + 1.
//
//   HalfEdges e = half_edges(mesh.triangles, uint32_t(mesh.vertices.size()));
//   if (e.twin[h] != kNoHalfEdge) ...   // the triangle across h is e.twin[h] / 3
#pragma once
#include <cstdint>
#include <limits>

#include "core/big_array.hpp"
#include "core/model.hpp"

namespace cdtgpu {

inline constexpr uint32_t kNoHalfEdge = std::numeric_limits<uint32_t>::max();

struct HalfEdges {
  BigArray<uint32_t> twin;    // kNoHalfEdge on the hull
  BigArray<uint32_t> start;   // per vertex v: the triangles starting at v are [start[v], start[v + 1])
  BigArray<uint32_t> corner;  // per vertex: one half-edge leaving it (the fan around it is walked by twins)
};

// A half-edge h by its edge (smaller vertex first): half-edges paired by a sort.
struct HalfEdgeKey {
  uint64_t edge;
  uint32_t h;
  bool operator<(const HalfEdgeKey& o) const { return edge != o.edge ? edge < o.edge : h < o.h; }
};

// A list out of canonical order is a logic_error. V: the vertex count (every id below it).
HalfEdges half_edges(const Triangles& ts, uint32_t V);

// Half-edge h's neighbours in its triangle, and its ends.
inline uint32_t next_of(uint32_t h) { return h / 3 * 3 + (h % 3 + 1) % 3; }
inline uint32_t prev_of(uint32_t h) { return h / 3 * 3 + (h % 3 + 2) % 3; }
inline uint32_t from_of(const Triangles& ts, uint32_t h) { return ts[h / 3][h % 3]; }
inline uint32_t to_of(const Triangles& ts, uint32_t h) { return ts[h / 3][(h % 3 + 1) % 3]; }

}  // namespace cdtgpu
