// plan_tiles (core/tile_plan.hpp).
#include "core/tile_plan.hpp"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include "core/select.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

namespace {
using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();
using Rect = TileRect;
constexpr uint64_t kSlabTilePoints = uint64_t(1) << 24;
constexpr double kMaxSlabAspect = 64;
}  // namespace

bool auto_slabs(uint64_t tiles, uint64_t max_points, double w, double h) {
  return max_points >= kSlabTilePoints && (h <= 0 || double(tiles) * h <= kMaxSlabAspect * w);
}

// Two-level k-d splits by count: columns of equal counts (vertex ids are in (x, y) order already), then each
// column, by median splits in (y, x) order on its own core, cut into cells of equal counts; as many columns
// as make the tiles about square over the data's extent. A cut goes between two consecutive vertices of that
// order, at the coordinate of the first one after it: every vertex strictly before that coordinate is on the
// near side, so by induction every vertex strictly inside a tile's rectangle is one of the tile's own. A
// binary tree over the cuts serves the segments' descent.
TilePlan plan_tiles(const Points& v, uint64_t max_points, TileShape shape, unsigned ramp) {
  const size_t n = v.size();
  TilePlan plan;
  // The height from about 2^20 of the vertices: it only shapes the columns (a pass over all of them read
  // 6 GB at 256M).
  const size_t stride = std::max<size_t>(1, n >> 20);
  auto [y0, y1] = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, (n + stride - 1) / stride, 1 << 12), std::pair<double, double>{kInf, -kInf},
      [&](const tbb::blocked_range<size_t>& r, std::pair<double, double> m) {
        for (size_t i = r.begin(); i < r.end(); ++i)
          m = {std::min(m.first, v[i * stride].y), std::max(m.second, v[i * stride].y)};
        return m;
      },
      [](auto a, auto b) {
        return std::pair<double, double>{std::min(a.first, b.first), std::max(a.second, b.second)};
      });
  const double w = v.back().x - v.front().x, h = y1 - y0;
  const uint64_t tiles = (n + max_points - 1) / max_points;
  // About square tiles: sqrt(tiles * w / h) columns, rounded down or up to whichever makes fewer cells (3 x 3 =
  // 9 tiles where 8 were asked, 2 x 4 = 8: on 2 cores the ninth tile ran alone, a ninth of the tiles' time).
  const double square = h <= 0 ? double(tiles) : w <= 0 ? 1.0 : std::sqrt(double(tiles) * w / h);
  auto cells_with = [&](uint64_t c) { return c * ((tiles + c - 1) / c); };
  const uint64_t down = std::clamp<uint64_t>(uint64_t(std::floor(square)), 1, tiles);
  const uint64_t up = std::clamp<uint64_t>(uint64_t(std::ceil(square)), 1, tiles);
  const uint64_t nearer = std::clamp<uint64_t>(uint64_t(std::llround(square)), 1, tiles);
  const uint64_t squares = cells_with(down) == cells_with(up) ? nearer
                           : cells_with(down) < cells_with(up) ? down
                                                               : up;
  // Slabs: at 1B points in 8 tiles of 2 x 4, the columns' selections took 1.4-2.0 s of the plan, before any tile,
  // and each tile's gather marked its whole column (500M ids); 8 slabs' longer border adds a few hundred
  // thousand vertices to a merge that the GPU takes in ~100 ms.
  const bool slabs = shape == TileShape::slabs || (shape == TileShape::automatic && auto_slabs(tiles, max_points, w, h));
  // Columns of equal counts; with a ramp, the first and the last slab cut into `ramp` each.
  std::vector<uint32_t> starts;
  if (slabs && ramp > 1 && tiles >= 2 && n / tiles >= ramp) {
    auto thin = [&](uint64_t lo, uint64_t hi) {
      for (uint64_t i = 0; i < ramp; ++i) starts.push_back(uint32_t(lo + (hi - lo) * i / ramp));
    };
    thin(0, n / tiles);
    for (uint64_t k = 1; k + 1 < tiles; ++k) starts.push_back(uint32_t(k * n / tiles));
    thin((tiles - 1) * n / tiles, n);
  } else {
    const uint64_t even = slabs ? tiles : squares;
    for (uint64_t c = 0; c < even; ++c) starts.push_back(uint32_t(c * n / even));
  }
  starts.push_back(uint32_t(n));
  const uint64_t columns = starts.size() - 1;
  plan.slabs = slabs;
  if (!slabs) {  // a slab's ids are its range: no order (4 GB written at 1B points)
    resize_unwritten(plan.order, n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) { plan.order[i] = uint32_t(i); });
  }
  auto column_start = [&](uint64_t c) { return starts[c]; };
  auto cell_count = [&](uint64_t c) {
    return std::max<uint64_t>(1, (column_start(c + 1) - column_start(c) + max_points - 1) / max_points);
  };
  // Each column on its own core: median splits by (y, x), their coordinates in preorder.
  std::vector<std::vector<double>> cuts(columns);
  tbb::parallel_for(uint64_t(0), columns, [&](uint64_t c) {
    // Without branches: a column's ids are in x order, so whether p is below q is a coin toss that a branch
    // mispredicts half the time (the partition's pass took 1.8x as long).
    auto by_y = [&](uint32_t p, uint32_t q) {
      const Point3 &a = v[p], &b = v[q];
      return (a.y < b.y) | ((a.y == b.y) & (a.x < b.x));
    };
    SelectScratch scratch;  // the column's, for all its splits
    std::function<void(uint32_t, uint32_t, uint64_t)> split = [&](uint32_t lo, uint32_t hi, uint64_t count) {
      if (count <= 1) return;
      const uint64_t half = count / 2;
      const uint32_t mid = lo + uint32_t(uint64_t(hi - lo) * half / count);
      const auto t = Clock::now();
      parallel_select(plan.order.data() + lo, plan.order.data() + mid, plan.order.data() + hi, by_y, &scratch);
      if (hi - lo >= (1u << 20))
        spdlog::debug("tiles: column {}'s split of {} ids in {:.0f} ms", c + 1, hi - lo, ms_since(t));
      cuts[c].push_back(v[plan.order[mid]].y);
      split(lo, mid, half);
      split(mid, hi, count - half);
    };
    split(column_start(c), column_start(c + 1), cell_count(c));
  });
  auto add = [&](const TileNode& node) {
    plan.nodes.push_back(node);
    return int32_t(plan.nodes.size() - 1);
  };
  // The tree of column c's cells, consuming its cuts in the preorder they were made in.
  size_t next_cut = 0;
  std::function<int32_t(uint64_t, uint32_t, uint32_t, uint64_t, Rect)> cells =
      [&](uint64_t c, uint32_t lo, uint32_t hi, uint64_t count, Rect rect) {
        const int32_t at = add(TileNode{rect, lo, hi, -1, -1, column_start(c), column_start(c + 1)});
        if (count <= 1) {
          plan.tiles.push_back(uint32_t(at));
          return at;
        }
        const uint64_t half = count / 2;
        const uint32_t mid = lo + uint32_t(uint64_t(hi - lo) * half / count);
        Rect below = rect, above = rect;
        below.y1 = above.y0 = cuts[c][next_cut++];
        const int32_t left = cells(c, lo, mid, half, below);
        const int32_t right = cells(c, mid, hi, count - half, above);
        plan.nodes[at].left = left, plan.nodes[at].right = right;
        return at;
      };
  std::function<int32_t(uint64_t, uint64_t, Rect)> cols = [&](uint64_t c0, uint64_t c1, Rect rect) {
    if (c1 - c0 == 1) {
      next_cut = 0;
      return cells(c0, column_start(c0), column_start(c1), cell_count(c0), rect);
    }
    const int32_t at = add(TileNode{rect, 0, 0, -1, -1, 0, 0});
    const uint64_t mid = (c0 + c1) / 2;
    Rect west = rect, east = rect;
    west.x1 = east.x0 = v[column_start(mid)].x;  // the ids of a column range are its (x, y) order
    const int32_t left = cols(c0, mid, west);
    const int32_t right = cols(mid, c1, east);
    plan.nodes[at].left = left, plan.nodes[at].right = right;
    return at;
  };
  cols(0, columns, Rect{});
  return plan;
}

}  // namespace cdtgpu
