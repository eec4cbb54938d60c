// tile_segments (core/tile_segments.hpp): the k-d tree's rectangles for squares, the id ranges for slabs.
#include "core/tile_segments.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include "core/predicates.hpp"
#include "core/touched.hpp"

namespace cdtgpu {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr size_t kSegmentBlock = 1 << 15;

// Whether segment ab meets the closed rectangle r, exactly: the part of r inside the segment's bounding box
// is met exactly when the segment's line does not pass strictly beside all four of its corners.
bool meets(const TileRect& r, const Point3& a, const Point3& b) {
  const double x0 = std::max(r.x0, std::min(a.x, b.x)), x1 = std::min(r.x1, std::max(a.x, b.x));
  const double y0 = std::max(r.y0, std::min(a.y, b.y)), y1 = std::min(r.y1, std::max(a.y, b.y));
  if (x0 > x1 || y0 > y1) return false;
  if (x0 == std::min(a.x, b.x) && x1 == std::max(a.x, b.x) && y0 == std::min(a.y, b.y) &&
      y1 == std::max(a.y, b.y))
    return true;  // the whole segment's box is in r
  int sides = 0;
  for (const pred::XY c : {pred::XY{x0, y0}, pred::XY{x1, y0}, pred::XY{x0, y1}, pred::XY{x1, y1}})
    sides |= 1 << (1 + pred::orient2d({a.x, a.y}, {b.x, b.y}, c));
  return sides != 1 && sides != 4;  // not all clockwise, not all counter-clockwise
}

// Segment i is (a, b) with a < b, and its first end is not below the one before (the merge input relies on it
// too: core/tiles.cpp).
void check_order(const std::vector<Edge>& segments, size_t i) {
  if (segments[i][0] >= segments[i][1] || (i > 0 && segments[i][0] < segments[i - 1][0]))
    throw std::logic_error("tiles: segment " + std::to_string(i) + " is not in order (a < b, sorted)");
}

// Squares: blocks of segments count their tiles (found in the k-d tree), then write them in block order, so
// each tile's list is in segment order without a sort.
void square_segments(const Points& v, const std::vector<Edge>& segments, const TilePlan& plan,
                     TileSegments& out) {
  const size_t tiles = plan.tiles.size();
  std::vector<uint32_t> tile_of_node(plan.nodes.size(), 0);
  for (size_t t = 0; t < tiles; ++t) tile_of_node[plan.tiles[t]] = uint32_t(t);
  auto for_tiles_of = [&](size_t i, auto&& f) {
    const Point3& a = v[segments[i][0]];
    const Point3& b = v[segments[i][1]];
    uint32_t stack[64];  // the tree's depth is about log2(tiles)
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const uint32_t at = stack[--top];
      const TileNode& node = plan.nodes[at];
      if (node.left < 0) {
        f(tile_of_node[at]);
        continue;
      }
      for (int32_t c : {node.right, node.left})
        if (meets(plan.nodes[c].rect, a, b)) stack[top++] = uint32_t(c);
    }
  };
  // The first pass keeps the tile of a segment that meets only one (nearly all), so the second reads that
  // instead of both ends again; for contour-like input the far end is far in memory (256M points: the plan
  // took 1.1 s longer with 64M segments than without).
  constexpr uint32_t kSeveral = UINT32_MAX;
  const size_t blocks = (segments.size() + kSegmentBlock - 1) / kSegmentBlock;
  std::vector<std::vector<uint32_t>> block_count(blocks);
  RawVector<uint32_t> only_tile;
  resize_unwritten(only_tile, segments.size());
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    std::vector<uint32_t>& count = block_count[b];
    count.assign(tiles, 0);
    const size_t end = std::min(segments.size(), (b + 1) * kSegmentBlock);
    for (size_t i = b * kSegmentBlock; i < end; ++i) {
      check_order(segments, i);
      if (i + 16 < end) __builtin_prefetch(&v[segments[i + 16][1]]);
      uint32_t met = 0, last = 0;
      for_tiles_of(i, [&](uint32_t t) { ++count[t], ++met, last = t; });
      only_tile[i] = met == 1 ? last : kSeveral;
    }
  });
  std::vector<size_t>& first = out.first;
  first.assign(tiles + 1, 0);
  for (size_t t = 0; t < tiles; ++t) {
    first[t + 1] = first[t];
    for (size_t b = 0; b < blocks; ++b) {
      const uint32_t c = block_count[b][t];
      block_count[b][t] = uint32_t(first[t + 1] - first[t]);  // the block's start within the tile's list
      first[t + 1] += c;
    }
  }
  resize_unwritten(out.ids, first[tiles]);  // every element written below
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    std::vector<uint32_t>& at = block_count[b];
    for (size_t i = b * kSegmentBlock; i < std::min(segments.size(), (b + 1) * kSegmentBlock); ++i)
      if (only_tile[i] != kSeveral)
        out.ids[first[only_tile[i]] + at[only_tile[i]]++] = uint32_t(i);
      else
        for_tiles_of(i, [&](uint32_t t) { out.ids[first[t] + at[t]++] = uint32_t(i); });
  });
  free_storage_on_all_cores(only_tile);
}

// Slabs (rectangles unbounded in y, side by side): meets() is then whether the x-ranges overlap, closed,
// since a segment passes through every vertical strip of its own box. That needs no coordinates: a segment (a
// < b) meets the slabs from a's to b's (ids are in (x, y) order and a slab's ids are a range), and one more
// on a side where that end lies on the slab's cut (the vertices on a cut are one id range; a slab of no width
// repeats its cut, so the step may repeat). The step to a neighbour keeps the closed rule, though such a
// segment cannot reach into the neighbour's open rectangle, where its final triangles lie: leaving it out
// changes no output. Nearly every segment meets only the slab of its first end: one pass finds the others,
// and no list of ids is written (at 1B points + 250M segments on the 2 x H200 host, 32 cores, counting and
// writing each segment's tiles took 530-630 ms).
void slab_segments(const Points& v, const std::vector<Edge>& segments, const TilePlan& plan,
                   TileSegments& out) {
  const size_t tiles = plan.tiles.size(), n = v.size();
  std::vector<uint32_t> slab_tile(tiles), slab_lo;    // in id (so x) order: the tile, its first id
  std::vector<std::pair<uint32_t, uint32_t>> on_cut;  // on_cut[k]: the ids with x equal to slab k's left cut
  std::iota(slab_tile.begin(), slab_tile.end(), 0u);
  std::sort(slab_tile.begin(), slab_tile.end(), [&](uint32_t p, uint32_t q) {
    return plan.nodes[plan.tiles[p]].lo < plan.nodes[plan.tiles[q]].lo;
  });
  uint32_t next = 0;
  double x1 = -kInf;
  for (uint32_t t : slab_tile) {
    const TileNode& node = plan.nodes[plan.tiles[t]];
    const TileRect& r = node.rect;
    if (r.y0 != -kInf || r.y1 != kInf || node.lo != next || r.x0 != x1 || (next == 0) != (r.x0 == -kInf))
      throw std::logic_error("tiles: slabs that are not strips side by side");
    next = node.hi;
    x1 = r.x1;
    slab_lo.push_back(node.lo);
    const auto at = [&](auto below) {
      return uint32_t(std::partition_point(v.begin(), v.end(), below) - v.begin());
    };
    on_cut.emplace_back(at([&](const Point3& p) { return p.x < r.x0; }),
                        at([&](const Point3& p) { return p.x <= r.x0; }));
  }
  if (next != n) throw std::logic_error("tiles: slabs that leave vertices out");
  slab_lo.push_back(uint32_t(n));  // slab k's ids: [slab_lo[k], slab_lo[k + 1])
  const size_t slabs = tiles;
  auto slab_of = [&](uint32_t id) {
    return size_t(std::upper_bound(slab_lo.begin(), slab_lo.end() - 1, id) - slab_lo.begin()) - 1;
  };
  auto on_left_cut = [&](size_t k, uint32_t id) {
    return k > 0 && k < slabs && id >= on_cut[k].first && id < on_cut[k].second;
  };
  // Slab k's own range: the segments whose first end it owns.
  std::vector<uint32_t> range_lo(slabs + 1);
  for (size_t k = 0; k <= slabs; ++k)
    range_lo[k] = uint32_t(std::partition_point(segments.begin(), segments.end(),
                                                [&](const Edge& e) { return e[0] < slab_lo[k]; }) -
                           segments.begin());
  // The others: (slab, segment) pairs per block, in segment order.
  const size_t blocks = (segments.size() + kSegmentBlock - 1) / kSegmentBlock;
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> found(blocks);
  tbb::parallel_for(size_t(0), blocks, [&](size_t blk) {
    const size_t begin = blk * kSegmentBlock, end = std::min(segments.size(), begin + kSegmentBlock);
    size_t k = slab_of(segments[begin][0]);
    for (size_t i = begin; i < end; ++i) {
      const uint32_t a = segments[i][0], b = segments[i][1];
      check_order(segments, i);
      while (a >= slab_lo[k + 1]) ++k;
      if (b < slab_lo[k + 1] && !on_left_cut(k, a) && !on_left_cut(k + 1, b)) continue;
      size_t lo = k, hi = slab_of(b);
      while (on_left_cut(lo, a)) --lo;
      while (on_left_cut(hi + 1, b)) ++hi;
      for (size_t s = lo; s <= hi; ++s)
        if (s != k) found[blk].emplace_back(uint32_t(s), uint32_t(i));
    }
  });
  out.range.resize(tiles);
  out.extra.assign(tiles, {});
  for (size_t k = 0; k < slabs; ++k) out.range[slab_tile[k]] = {range_lo[k], range_lo[k + 1]};
  for (const auto& pairs : found)
    for (const auto& [s, i] : pairs) out.extra[slab_tile[s]].push_back(i);
}

}  // namespace

std::span<const uint32_t> TileSegments::of(size_t t, RawVector<uint32_t>& scratch) const {
  if (range.empty()) return {ids.data() + first[t], first[t + 1] - first[t]};
  const auto [lo, hi] = range[t];
  const std::vector<uint32_t>& more = extra[t];
  const size_t below = size_t(std::lower_bound(more.begin(), more.end(), lo) - more.begin());
  scratch.clear();
  resize_unwritten(scratch, more.size() + (hi - lo));
  std::copy(more.begin(), more.begin() + below, scratch.begin());
  uint32_t* const at = scratch.data() + below;
  tbb::parallel_for(tbb::blocked_range<uint32_t>(lo, hi, 1 << 20),
                    [&](const tbb::blocked_range<uint32_t>& r) {
                      std::iota(at + (r.begin() - lo), at + (r.end() - lo), r.begin());
                    });
  std::copy(more.begin() + below, more.end(), at + (hi - lo));
  return {scratch.data(), scratch.size()};
}

TileSegments tile_segments(const Points& v, const std::vector<Edge>& segments, const TilePlan& plan) {
  TileSegments out;
  if (plan.slabs)
    slab_segments(v, segments, plan, out);
  else
    square_segments(v, segments, plan, out);
  return out;
}

}  // namespace cdtgpu
