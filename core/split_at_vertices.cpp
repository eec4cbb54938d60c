#include "core/split_at_vertices.hpp"

#include <algorithm>

#include "core/predicates.hpp"

namespace cdtgpu {

VertexSplits split_at_vertices(const Points& vertices, const std::vector<Edge>& segments,
                               std::vector<std::array<uint32_t, 3>> found) {
  VertexSplits out;
  std::vector<uint32_t> on;  // every vertex found inside a segment or piece
  for (const auto& [a, b, v] : found) {
    if (std::binary_search(segments.begin(), segments.end(), Edge{a, b})) out.split.push_back({a, b});
    on.push_back(v);
  }
  std::sort(out.split.begin(), out.split.end());
  out.split.erase(std::unique(out.split.begin(), out.split.end()), out.split.end());
  std::sort(on.begin(), on.end());
  on.erase(std::unique(on.begin(), on.end()), on.end());

  auto xy = [&](uint32_t i) { return pred::XY{vertices[i].x, vertices[i].y}; };
  for (const auto& [a, b] : out.split) {
    // A vertex inside a-b lies between its ends in the (x, y) order, and so do the ids: in order along it.
    uint32_t from = a;
    for (auto it = std::upper_bound(on.begin(), on.end(), a); it != on.end() && *it < b; ++it) {
      if (pred::orient2d(xy(a), xy(b), xy(*it)) != 0) continue;
      out.pieces.push_back({from, *it});
      from = *it;
      ++out.splits;
    }
    out.pieces.push_back({from, b});
  }
  std::sort(out.pieces.begin(), out.pieces.end());
  out.pieces.erase(std::unique(out.pieces.begin(), out.pieces.end()), out.pieces.end());
  return out;
}

}  // namespace cdtgpu
