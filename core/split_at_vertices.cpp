#include "core/split_at_vertices.hpp"

#include <algorithm>
#include <execution>

#include "core/compact.hpp"
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

std::vector<Edge> with_pieces(const std::vector<Edge>& segments, const VertexSplits& s) {
  auto is_split = [&](size_t i) { return std::binary_search(s.split.begin(), s.split.end(), segments[i]); };
  const std::vector<Edge> kept = compact<Edge>(
      segments.size(), [&](size_t i) { return is_split(i) ? 0 : 1; },
      [&](size_t i, Edge* at) {
        if (!is_split(i)) *at++ = segments[i];
        return at;
      });
  std::vector<Edge> all(kept.size() + s.pieces.size());
  std::merge(std::execution::par, kept.begin(), kept.end(), s.pieces.begin(), s.pieces.end(), all.begin());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

}  // namespace cdtgpu
