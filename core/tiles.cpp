// tiled_cdt: k-d tiles by vertex count, each tile's CDT with its final triangles kept, the rest merged by one
// more CDT whose constraints include the final region's border. Why each step is exact: docs/tiles.md.
// Cost: the tiles' CDTs (in parallel) plus the merge, which holds the vertices along the tile borders and
// beside long segments: a few per cent of the input at uniform density (docs/tiles.md has the figures).
#include "core/tiles.hpp"

#include <CGAL/Interval_nt.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <future>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <span>
#include <thread>

#include <spdlog/spdlog.h>

#include "core/canonical.hpp"
#include "core/compact.hpp"
#include "core/host_memory.hpp"
#include "core/parallel.hpp"
#include "core/predicates.hpp"
#include "core/split_at_vertices.hpp"
#include "core/tile_merge.hpp"
#include "core/tile_plan.hpp"
#include "core/tile_segments.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kInf = std::numeric_limits<double>::infinity();

using Rect = TileRect;
using Node = TileNode;
using Plan = TilePlan;

// Whether the closed circumdisk of abc lies in the open interior of r, in interval arithmetic: a triangle too
// flat or too close to the border to tell is taken as not final, which only makes the merge larger.
bool disk_inside_intervals(const Point3& a, const Point3& b, const Point3& c, const Rect& r) {
  CGAL::Protect_FPU_rounding<true> upward;
  using I = CGAL::Interval_nt_advanced;
  const I ax(a.x), ay(a.y);
  const I bx = I(b.x) - ax, by = I(b.y) - ay, cx = I(c.x) - ax, cy = I(c.y) - ay;
  const I d = 2 * (bx * cy - by * cx);
  if (!(d.inf() > 0 || d.sup() < 0)) return false;
  const I b2 = CGAL::square(bx) + CGAL::square(by), c2 = CGAL::square(cx) + CGAL::square(cy);
  const I ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;  // the centre, from a
  const I r2 = CGAL::square(ux) + CGAL::square(uy);
  auto clear = [&](const I& gap) { return gap.inf() > 0 && (CGAL::square(gap) - r2).inf() > 0; };
  return (r.x0 == -kInf || clear(ax + ux - I(r.x0))) && (r.x1 == kInf || clear(I(r.x1) - ax - ux)) &&
         (r.y0 == -kInf || clear(ay + uy - I(r.y0))) && (r.y1 == kInf || clear(I(r.y1) - ay - uy));
}

// The same, decided in plain doubles when the answer is clear by more than a bound on their error, else by
// disk_inside_intervals (~3x slower). With u = 2^-53 and M the largest of |b - a|, |c - a| per coordinate,
// first order: d = 2((b-a) x (c-a)) is off by at most 16 u M^2 and each numerator of the centre by 36 u M^3
// (the differences' own rounding included); so the centre (from a) is off by
//   e <= (36 u M^3 + |centre| 16 u M^2) / |d| + u |centre|
// per coordinate, the radius by 1.5 e + 3 u r, a gap to a side by e + 2 u (|a - side| + |centre|). Every
// bound is taken 4x, and d within 64x its error bound goes to intervals (the second-order terms stay tiny).
bool disk_inside(const Point3& a, const Point3& b, const Point3& c, const Rect& r) {
  constexpr double u = 0x1p-53;
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  const double m = std::max({std::abs(bx), std::abs(by), std::abs(cx), std::abs(cy)});
  const double d = 2 * (bx * cy - by * cx);
  const double d_err = 4 * 16 * u * m * m;
  if (!(std::abs(d) > 64 * d_err)) return disk_inside_intervals(a, b, c, r);
  const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  const double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
  const double centre = std::max(std::abs(ux), std::abs(uy));
  const double e = 4 * ((36 * u * m * m * m + centre * 16 * u * m * m) / std::abs(d) + u * centre);
  const double radius = std::sqrt(ux * ux + uy * uy);
  const double radius_err = 4 * (1.5 * e + 3 * u * radius);
  // +1: clear of the side by more than the error; -1: certainly not clear; 0: too close to tell.
  auto side = [&](double offset, double gap) {
    const double slack = e + radius_err + 4 * 2 * u * (std::abs(offset) + centre);
    return gap - radius > slack ? 1 : gap - radius < -slack ? -1 : 0;
  };
  int worst = 1;
  if (r.x0 != -kInf) worst = std::min(worst, side(a.x - r.x0, (a.x - r.x0) + ux));
  if (worst >= 0 && r.x1 != kInf) worst = std::min(worst, side(r.x1 - a.x, (r.x1 - a.x) - ux));
  if (worst >= 0 && r.y0 != -kInf) worst = std::min(worst, side(a.y - r.y0, (a.y - r.y0) + uy));
  if (worst >= 0 && r.y1 != kInf) worst = std::min(worst, side(r.y1 - a.y, (r.y1 - a.y) - uy));
  if (worst == 0) return disk_inside_intervals(a, b, c, r);
  return worst > 0;
}

// The hull chains of p[ids] (ids in (x, y) order): the lower one left to right, then the upper one right to
// left, collinear boundary points kept (a triangulation's hull edges join consecutive ones). Returns the
// closed cycle, its first point repeated at the end.
std::vector<uint32_t> hull_cycle(const Points& p, const std::vector<uint32_t>& ids) {
  auto turn = [&](uint32_t a, uint32_t b, uint32_t c) {
    return pred::orient2d({p[a].x, p[a].y}, {p[b].x, p[b].y}, {p[c].x, p[c].y});
  };
  std::vector<uint32_t> h;
  if (ids.empty()) return h;
  for (int pass = 0; pass < 2; ++pass) {
    const size_t base = h.size();
    for (size_t k = 0; k < ids.size(); ++k) {
      const uint32_t i = ids[pass == 0 ? k : ids.size() - 1 - k];
      while (h.size() >= base + 2 && turn(h[h.size() - 2], h.back(), i) < 0) h.pop_back();
      h.push_back(i);
    }
    if (pass == 0) h.pop_back();  // the last point starts the upper chain
  }
  return h;
}

// The edges of the convex hull of sorted points, counter-clockwise, as directed keys a << 32 | b. A point on
// the whole hull is on the hull of any run of the order that holds it, so runs' hull points are found on all
// cores and the hull of those few is the answer (64M points: 5.7 s on one core before).
std::vector<uint64_t> hull_edges(const Points& p) {
  constexpr size_t kRun = 1 << 16;
  const size_t runs = (p.size() + kRun - 1) / kRun;
  std::vector<std::vector<uint32_t>> on_hull(runs);
  tbb::parallel_for(size_t(0), runs, [&](size_t r) {
    std::vector<uint32_t> ids;
    for (size_t i = r * kRun; i < std::min(p.size(), (r + 1) * kRun); ++i) ids.push_back(uint32_t(i));
    on_hull[r] = hull_cycle(p, ids);
    std::sort(on_hull[r].begin(), on_hull[r].end());
    on_hull[r].erase(std::unique(on_hull[r].begin(), on_hull[r].end()), on_hull[r].end());
  });
  std::vector<uint32_t> candidates;  // in (x, y) order: the runs are consecutive
  for (const auto& r : on_hull) candidates.insert(candidates.end(), r.begin(), r.end());
  const std::vector<uint32_t> h = hull_cycle(p, candidates);
  std::vector<uint64_t> edges;
  for (size_t k = 0; k + 1 < h.size(); ++k) edges.push_back(uint64_t(h[k]) << 32 | h[k + 1]);
  std::sort(edges.begin(), edges.end());
  return edges;
}

// Without the triangulator's neighbours: marks bit k of a final triangle whose edge a->b (from vertex k) is
// not shared with another final triangle. Such an edge is shared with a non-final triangle (b->a is one of
// its edges) or lies on the tile's hull (a->b is a hull edge); both its ends then touch a non-final triangle
// or the hull, which a byte per vertex tells, so nearly every edge is settled without a look-up.
void mark_border(const Triangles& triangles, const Points& local,
                 std::vector<uint8_t>& final_mask) {
  const size_t nt = triangles.size();
  const std::vector<uint64_t> hull = hull_edges(local);
  std::vector<uint8_t> touched(local.size(), 0);
  for (uint64_t e : hull) touched[e >> 32] = 1;
  std::vector<uint64_t> non_final = compact<uint64_t>(
      nt, [&](size_t i) { return final_mask[i] ? 0 : 3; },
      [&](size_t i, uint64_t* at) {
        if (final_mask[i]) return at;
        const Triangle& t = triangles[i];
        for (int k = 0; k < 3; ++k) *at++ = uint64_t(t[k]) << 32 | t[(k + 1) % 3];
        return at;
      });
  for (uint64_t e : non_final) touched[e >> 32] = 1;
  tbb::parallel_sort(non_final.begin(), non_final.end());
  auto has = [](const std::vector<uint64_t>& keys, uint64_t key) {
    return std::binary_search(keys.begin(), keys.end(), key);
  };
  tbb::parallel_for(size_t(0), nt, [&](size_t i) {
    if (!final_mask[i]) return;
    const Triangle& t = triangles[i];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (!touched[a] || !touched[b]) continue;
      if (has(non_final, uint64_t(b) << 32 | a) || has(hull, uint64_t(a) << 32 | b))
        final_mask[i] |= uint8_t(1 << k);
    }
  });
}

// A tile's own points and room for the far endpoints of the segments that cross into it.
uint64_t staging_room(uint64_t points) { return points + points / 64 + 1024; }

// One tile: its CDT, its final triangles (vertex ids of the whole) and their border.
struct TileResult {
  Triangles final_triangles;
  std::vector<Edge> border;
  std::vector<std::array<uint32_t, 3>> split;  // TileFinal::split
  std::vector<uint32_t> merge_ids;  // a slab's: its vertices in the merge (unmarked_ids), sorted
  double cdt_ms = 0, other_ms = 0;
  double gather_ms = 0, final_ms = 0;  // parts of other_ms: the tile's input, the host's final test and border
};

// A tile's final triangles and border, timed into r: its CDT from the finalizer.
TileFinal finalize_tile(const TileFinalizer& finalize, const TileJob& job, TileResult& r) {
  const auto t = Clock::now();
  TileFinal f = finalize(job);
  r.cdt_ms = ms_since(t);
  return f;
}

// The same from the triangulator's whole CDT of the tile, tested here.
TileFinal final_on_host(const Points& v, std::span<const uint32_t> ids,
                        std::span<const Edge> tile_segments, const Rect& rect, const TileTriangulator& triangulate,
                        const std::string& name, TileResult& r) {
  auto t = Clock::now();
  Points local;
  resize_unwritten(local, ids.size());
  tbb::parallel_for(size_t(0), ids.size(), [&](size_t i) { local[i] = v[ids[i]]; });
  const std::vector<Edge> segments(tile_segments.begin(), tile_segments.end());  // the triangulator's type
  r.gather_ms += ms_since(t);
  t = Clock::now();
  TileMesh mesh = triangulate(local, segments, name);
  r.cdt_ms = ms_since(t);
  t = Clock::now();
  const Triangles& triangles = mesh.triangles;
  const size_t nt = triangles.size();
  // Bit 3: final; bit k < 3: its edge k is on the final region's border.
  std::vector<uint8_t> final_mask(nt, 0);
  tbb::parallel_for(size_t(0), nt, [&](size_t i) {
    const Triangle& tr = triangles[i];
    final_mask[i] = disk_inside(local[tr[0]], local[tr[1]], local[tr[2]], rect) ? 8 : 0;
  });
  if (!mesh.neighbours.empty()) {
    tbb::parallel_for(size_t(0), nt, [&](size_t i) {
      if (!final_mask[i]) return;
      for (int k = 0; k < 3; ++k) {
        const uint32_t nb = mesh.neighbours[3 * i + k];
        if (nb == UINT32_MAX || !final_mask[nb]) final_mask[i] |= uint8_t(1 << k);
      }
    });
  } else {
    mark_border(triangles, local, final_mask);
  }
  r.final_ms = ms_since(t);
  TileFinal f;
  f.triangles = compact_as<Triangles>(
      nt, [&](size_t i) { return final_mask[i] ? 1 : 0; },
      [&](size_t i, Triangle* at) {
        if (final_mask[i]) *at++ = triangles[i];
        return at;
      });
  f.border = compact<Edge>(
      nt, [&](size_t i) { return std::popcount(unsigned(final_mask[i] & 7)); },
      [&](size_t i, Edge* at) {
        for (int k = 0; k < 3; ++k)
          if (final_mask[i] & (1 << k)) *at++ = {triangles[i][k], triangles[i][(k + 1) % 3]};
        return at;
      });
  canonicalize_triangles_one_core(f.triangles, local.size());  // a GPU tile's come sorted already
  return f;
}

// A tile's input: its vertex ids of the whole (sorted) and its segments in local ids.
struct GatheredTile {
  RawVector<uint32_t> ids;
  RawVector<Edge> local_segments;
  double gather_ms = 0;
};

GatheredTile gather_tile(const std::vector<Edge>& segments, const Plan& plan, const Node& node,
                         std::span<const uint32_t> tile_segments) {
  const auto t0 = Clock::now();
  // The tile's vertex ids, sorted: its own lie in its column's id range (a column is a range of the (x, y)
  // order); the segments' endpoints outside that range (few) are sorted apart. A slab owns its whole column;
  // a cell's own ids and the segments' endpoints in the column are marked in a byte map and read back in
  // order, and the map's ranks give the segments' local ids.
  const uint32_t c0 = node.column_lo, c1 = node.column_hi;
  const size_t span = c1 - c0;
  const bool slab = node.hi - node.lo == span;
  auto inside = [&](uint32_t id) { return id >= c0 && id < c1; };
  std::vector<uint32_t> outside = compact<uint32_t>(
      tile_segments.size(),
      [&](size_t i) {
        return !inside(segments[tile_segments[i]][0]) + !inside(segments[tile_segments[i]][1]);
      },
      [&](size_t i, uint32_t* at) {
        for (uint32_t id : segments[tile_segments[i]])
          if (!inside(id)) *at++ = id;
        return at;
      });
  std::sort(outside.begin(), outside.end());
  outside.erase(std::unique(outside.begin(), outside.end()), outside.end());
  const size_t below = size_t(std::lower_bound(outside.begin(), outside.end(), c0) - outside.begin());
  // Raw, on huge pages: a column at 1B points in 8 tiles is 500M ids, and this map and the ranks below were
  // 2.5 GB of 4 KiB page faults a tile (a vector would also value-initialise them on one core).
  RawVector<uint8_t> mark;
  std::vector<uint32_t> own;
  if (!slab) {
    resize_touched(mark, span);  // zeroed on all cores
    tbb::parallel_for(node.lo, node.hi, [&](uint32_t i) { mark[plan.order[i] - c0] = 1; });
    tbb::parallel_for(size_t(0), tile_segments.size(), [&](size_t i) {
      for (uint32_t id : segments[tile_segments[i]])
        if (inside(id)) std::atomic_ref<uint8_t>(mark[id - c0]).store(1, std::memory_order_relaxed);
    });
    own = compact<uint32_t>(
        span, [&](size_t i) { return mark[i]; },
        [&](size_t i, uint32_t* at) {
          if (mark[i]) *at++ = c0 + uint32_t(i);
          return at;
        });
  }
  const size_t owned = slab ? span : own.size();
  // Outside ids below the column, the column's, those above: written on all cores into unwritten memory.
  RawVector<uint32_t> ids;
  ids.resize(outside.size() + owned);
  advise_huge_pages(ids.data(), ids.size() * sizeof(uint32_t));
  std::copy(outside.begin(), outside.begin() + below, ids.begin());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, owned, 1 << 20), [&](const tbb::blocked_range<size_t>& r) {
    uint32_t* at = ids.data() + below;
    if (slab)
      std::iota(at + r.begin(), at + r.end(), c0 + uint32_t(r.begin()));
    else
      std::copy(own.begin() + r.begin(), own.begin() + r.end(), at + r.begin());
  });
  std::copy(outside.begin() + below, outside.end(), ids.begin() + below + owned);
  const size_t nl = ids.size();
  RawVector<uint32_t> rank;
  if (!slab) {
    resize_unwritten(rank, span);  // set, and read, only at the tile's ids in the column
    tbb::parallel_for(size_t(0), nl, [&](size_t i) {
      if (inside(ids[i])) rank[ids[i] - c0] = uint32_t(i);
    });
  }
  auto local_of = [&](uint32_t id) {
    if (!inside(id)) return uint32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
    return slab ? uint32_t(below + (id - c0)) : rank[id - c0];
  };
  // Unwritten: value-initialised, 31M segments (250 MB) were zeroed on one core in the tiles' serial gather.
  RawVector<Edge> local_segments;
  resize_unwritten(local_segments, tile_segments.size());
  tbb::parallel_for(size_t(0), tile_segments.size(), [&](size_t i) {
    local_segments[i] = {local_of(segments[tile_segments[i]][0]), local_of(segments[tile_segments[i]][1])};
  });
  tbb::parallel_sort(local_segments.begin(), local_segments.end());
  return GatheredTile{std::move(ids), std::move(local_segments), ms_since(t0)};
}

// The final region's vertices: every vertex of the final triangles, marked 1 (tiles mark theirs concurrently).
void mark_final(const Triangles& final_triangles, std::vector<uint8_t>& in_final) {
  tbb::parallel_for(size_t(0), final_triangles.size(), [&](size_t i) {
    for (uint32_t id : final_triangles[i]) std::atomic_ref<uint8_t>(in_final[id]).store(1, std::memory_order_relaxed);
  });
}

// The ids in [lo, hi) that are in the merge: in_final cleared at the border's vertices (there and then on it marks
// the vertices that are not), those not marked, sorted. Read 8 marks at a time: nearly all are 1.
std::vector<uint32_t> unmarked_ids(std::vector<uint8_t>& in_final, std::span<const Edge> border, uint32_t lo,
                                   uint32_t hi) {
  tbb::parallel_for(size_t(0), border.size(), [&](size_t i) {
    for (uint32_t id : border[i]) std::atomic_ref<uint8_t>(in_final[id]).store(0, std::memory_order_relaxed);
  });
  constexpr uint64_t kOnes = 0x0101010101010101;
  const uint64_t w0 = (uint64_t(lo) + 7) / 8, w1 = std::max<uint64_t>(w0, hi / 8);  // whole words; the ends alone
  auto word_at = [&](size_t w) {
    uint64_t word;
    std::memcpy(&word, in_final.data() + 8 * w, 8);
    return ~word & kOnes;  // a 1 in the low bit of each vertex's byte that is in the merge
  };
  std::vector<uint32_t> ids;
  for (uint64_t i = lo; i < std::min<uint64_t>(hi, 8 * w0); ++i)
    if (!in_final[i]) ids.push_back(uint32_t(i));
  std::vector<uint32_t> middle = compact<uint32_t>(
      w1 - w0, [&](size_t w) { return std::popcount(word_at(w0 + w)); },
      [&](size_t w, uint32_t* at) {
        for (uint64_t m = word_at(w0 + w); m; m &= m - 1) *at++ = uint32_t(8 * (w0 + w) + std::countr_zero(m) / 8);
        return at;
      });
  ids.insert(ids.end(), middle.begin(), middle.end());
  for (uint64_t i = std::max<uint64_t>(lo, 8 * w1); i < hi; ++i)
    if (!in_final[i]) ids.push_back(uint32_t(i));
  return ids;
}

TileResult finish_tile(const Points& v, GatheredTile g, const Node& node, const TileTriangulator& triangulate,
                       const TileFinalizer& finalize, const std::string& name, std::vector<uint8_t>& in_final,
                       const std::shared_future<void>& in_final_zeroed, bool unresolved, bool slab) {
  const auto t0 = Clock::now();
  const RawVector<uint32_t>& ids = g.ids;
  TileResult r;
  r.gather_ms = g.gather_ms;
  TileFinal f = finalize ? finalize_tile(finalize, TileJob{v, ids, g.local_segments, node.rect, name, unresolved}, r)
                         : final_on_host(v, ids, g.local_segments, node.rect, triangulate, name, r);
  // Back to the whole's ids, in place (a fresh 1.5 GB array for a 64M-point tile was zeroed on one core), unless
  // the finalizer did it: sorted ids keep a canonical list canonical.
  r.final_triangles = std::move(f.triangles);
  if (!f.global_ids)
    tbb::parallel_for(size_t(0), r.final_triangles.size(), [&](size_t i) {
      for (uint32_t& v : r.final_triangles[i]) v = ids[v];
    });
  r.border = std::move(f.border);
  tbb::parallel_for(size_t(0), r.border.size(), [&](size_t i) {
    for (uint32_t& v : r.border[i]) v = ids[v];
  });
  r.split = std::move(f.split);
  for (auto& split : r.split)
    for (uint32_t& v : split) v = ids[v];
  // A final triangle's vertices are strictly inside the tile, so they are its own: no other tile writes them.
  in_final_zeroed.get();  // rethrows its error
  mark_final(r.final_triangles, in_final);
  // A slab's border and unmarked vertices are its own ids too (its column): its merge vertices, found beside the
  // other tiles (a pass over every vertex's mark after the last tile took 46-57 ms at 1B points on one H200).
  if (slab) r.merge_ids = unmarked_ids(in_final, r.border, node.lo, node.hi);
  r.other_ms = r.gather_ms + ms_since(t0) - r.cdt_ms;
  return r;
}

}  // namespace

TileTriangulator cgal_tile_triangulator() {
  return [](const Points& v, const std::vector<Edge>& s, std::string_view) {
    TileMesh m;
    m.triangles = cdt_of_graph(v, s, &m.neighbours);
    return m;
  };
}

TileFinalizer host_finalizer(TileTriangulator triangulate) {
  return [triangulate = std::move(triangulate)](const TileJob& job) {
    TileResult timing;
    return final_on_host(job.all, job.ids, job.segments, job.rect, triangulate, std::string(job.what), timing);
  };
}

namespace {

// Ranks in a sorted list of ids without an array as long as the whole: where each block of 256 whole ids starts in
// the list, and a search inside the block. An array of every vertex's local id (5 GB at 1B points) cost 130-210
// ms of page faults and ~0.2 s to free on one core, serial work after the tiles.
class SortedRanks {
 public:
  SortedRanks(std::span<const uint32_t> ids, uint64_t n) : ids_(ids), start_((n >> kShift) + 2) {
    // Block b starts at the first id at or past b << kShift: each i writes the blocks from the one after its
    // predecessor's up to its own, so every block is written once.
    const size_t m = ids.size(), blocks = start_.size();
    tbb::parallel_for(size_t(0), m + 1, [&](size_t i) {
      const size_t from = i == 0 ? 0 : (ids[i - 1] >> kShift) + 1, to = i == m ? blocks - 1 : ids[i] >> kShift;
      for (size_t b = from; b <= to; ++b) start_[b] = uint32_t(i);
    });
  }
  // The rank of `id`, which is in the list.
  uint32_t operator()(uint32_t id) const {
    const uint32_t* lo = ids_.data() + start_[id >> kShift];
    const uint32_t* hi = ids_.data() + start_[(id >> kShift) + 1];
    return uint32_t(std::lower_bound(lo, hi, id) - ids_.data());
  }

 private:
  static constexpr unsigned kShift = 8;
  std::span<const uint32_t> ids_;
  RawVector<uint32_t> start_;
};

// What the merge triangulates (tiling.md): the vertices not inside the final region with the border's, the
// segments between them (a segment with an end inside the final region lies inside it; split ones as their
// pieces) and the border edges, in the merge's own ids. `in_final` is read, then freed. For slabs the merge's
// vertices are found already (`slab_ids`: each slab's unmarked_ids as it finished, in id order).
struct MergeJob {
  std::vector<uint32_t> ids;  // the merge's vertex i is the level's ids[i]
  Points vertices;
  std::vector<Edge> segments, border;  // border: directed as the tiles gave it
};

MergeJob merge_job(const Points& v, const std::vector<Edge>& segments, const std::vector<Edge>& border,
                   const VertexSplits& split_segments, std::vector<uint8_t>& in_final, bool slabs,
                   std::vector<uint32_t> slab_ids) {
  const size_t n = v.size();
  StepTimes steps;  // -v: where the merge's input goes
  const std::vector<Edge>& split_ones = split_segments.split;
  auto not_split = [&](const Edge& e) {
    return split_ones.empty() || !std::binary_search(split_ones.begin(), split_ones.end(), e);
  };
  // The merge's vertices: those not in the final region, and the border's (in_final cleared there, so from here
  // on it marks the vertices that are not in the merge). Slabs found their own as they finished.
  std::vector<uint32_t> ids = std::move(slab_ids);
  if (!slabs) ids = unmarked_ids(in_final, border, 0, uint32_t(n));
  steps.add("vertices");
  const SortedRanks local_of(ids, n);  // the merge's id of a merge vertex
  Points merge_vertices(ids.size());
  tbb::parallel_for(size_t(0), ids.size(), [&](size_t i) { merge_vertices[i] = v[ids[i]]; });
  steps.add("local ids");
  // The segments between them: such a segment's first end is a merge vertex, and segments are sorted by it
  // (tile_segments checks), so each merge vertex's are found from the last one's by a galloping search, not by a
  // pass over every segment (250M at 1B points).
  constexpr size_t kIdBlock = 1 << 12;
  RawVector<uint32_t> segments_from(ids.size() + 1);  // merge vertex i's segments: from [i] up to [i + 1]
  tbb::parallel_for(size_t(0), (ids.size() + kIdBlock - 1) / kIdBlock, [&](size_t blk) {
    const size_t end = std::min(ids.size(), (blk + 1) * kIdBlock);
    auto first_end_below = [&](uint32_t id) { return [id](const Edge& e) { return e[0] < id; }; };
    const auto from = segments.begin();
    size_t at = size_t(std::partition_point(from, segments.end(), first_end_below(ids[blk * kIdBlock])) - from);
    for (size_t i = blk * kIdBlock; i < end; ++i) {
      size_t step = 1, hi = at;
      while (hi < segments.size() && segments[hi][0] < ids[i]) hi = std::min(segments.size(), at + (step *= 2));
      at = size_t(std::partition_point(from + at, from + hi, first_end_below(ids[i])) - from);
      segments_from[i] = uint32_t(at);
    }
  });
  segments_from[ids.size()] = uint32_t(segments.size());
  steps.add("segments found");
  // The border edges and the split segments' pieces between merge vertices, in local ids, listed under their
  // smaller end (extra[extra_from[i] ..], their larger ends, sorted) and merged there with that vertex's segments:
  // the merge's segments come out sorted and unique. Appended and sorted whole, they took ~0.6 s of a
  // 4.5M-vertex merge's input on 2 cores; with a sort of their keys alone (smaller << 32 | larger) this step took
  // 76-101 ms of a 5.9M-vertex merge's on 32 threads, listed on all cores 24-27 (a vertex's few sorted in place;
  // repeats are dropped below).
  std::vector<Edge> local_border;
  assign_on_all_cores(local_border, border.size(), 0,
                      [&](size_t i) { return Edge{local_of(border[i][0]), local_of(border[i][1])}; });
  std::vector<Edge> pieces;
  for (const Edge& e : split_segments.pieces)
    if (!in_final[e[0]] && !in_final[e[1]]) pieces.push_back({local_of(e[0]), local_of(e[1])});
  const size_t extras = pieces.size() + border.size();
  auto extra_edge = [&](size_t k) -> const Edge& {
    return k < pieces.size() ? pieces[k] : local_border[k - pieces.size()];
  };
  RawVector<uint32_t> extra_from, extra;
  auto smaller = [&](size_t k) { return std::min(extra_edge(k)[0], extra_edge(k)[1]); };
  group(extras, ids.size(), smaller, extra_from, extra, /*ascending=*/false);  // sorted by larger end below
  each(extras, [&](size_t j) { extra[j] = std::max(extra_edge(extra[j])[0], extra_edge(extra[j])[1]); });
  each(ids.size(), [&](size_t i) { std::sort(extra.begin() + extra_from[i], extra.begin() + extra_from[i + 1]); });
  steps.add("border and pieces");
  // Merge vertex i's segments to larger ends, each once, in order: its own (sorted already) and the extra ones.
  auto each_segment_of = [&](size_t i, auto&& f) {
    const uint32_t* x = extra.data() + extra_from[i];
    const uint32_t* const x1 = extra.data() + extra_from[i + 1];
    uint64_t last = ~uint64_t(0);
    auto put = [&](uint32_t to) {
      if (to != last) f(to);
      last = to;
    };
    for (size_t j = segments_from[i]; j < segments_from[i + 1] && segments[j][0] == ids[i]; ++j) {
      if (in_final[segments[j][1]] || !not_split(segments[j])) continue;
      const uint32_t to = local_of(segments[j][1]);
      for (; x != x1 && *x < to; ++x) put(*x);
      put(to);
    }
    for (; x != x1; ++x) put(*x);
  };
  std::vector<Edge> merge_segments = compact<Edge>(
      ids.size(),
      [&](size_t i) {
        size_t k = 0;
        each_segment_of(i, [&](uint32_t) { ++k; });
        return k;
      },
      [&](size_t i, Edge* at) {
        each_segment_of(i, [&](uint32_t to) { *at++ = {uint32_t(i), to}; });
        return at;
      });
  free_storage_on_all_cores(in_final);
  steps.add("segments");
  spdlog::debug("the merge's input, ms: {}", steps.text());
  return MergeJob{std::move(ids), std::move(merge_vertices), std::move(merge_segments), std::move(local_border)};
}

// The pieces piece(order[0]), piece(order[1]), ... one after another, written on all cores.
template <class T, class Piece>
std::vector<T> joined(const std::vector<size_t>& order, Piece&& piece) {
  std::vector<size_t> at(order.size() + 1, 0);
  for (size_t k = 0; k < order.size(); ++k) at[k + 1] = at[k] + piece(order[k]).size();
  std::vector<T> out;
  assign_on_all_cores(out, at.back(), 0, [&](size_t i) {
    const size_t k = size_t(std::upper_bound(at.begin(), at.end(), i) - at.begin()) - 1;
    return piece(order[k])[i - at[k]];
  });
  return out;
}

// tiled_cdt's triangles in canonical order: each tile's final ones and the merge's, merged by RunMerge
// (core/tile_merge), or at the first level with options.in_runs left in the runs.
OrderedRuns tiled_runs(const Points& v, const std::vector<Edge>& segments,
                                              const TileOptions& options, const TileTriangulator& triangulate,
                                              TileStats& s) {
  const uint64_t n = v.size();
  const uint64_t level = s.levels + 1;
  if (options.max_tile_points < 3 || n <= options.max_tile_points) {
    // Nothing would check an unresolved input's one piece: left to the resolve.
    if (level == 1 && options.unresolved) throw UnresolvedTile("one piece, not tiles: the resolve checks it");
    const auto t = Clock::now();
    Triangles all = triangulate(v, segments, "the whole input").triangles;
    canonicalize_triangles(all);
    s.merge_ms = ms_since(t);
    s.merge_vertices = n;
    s.merge_segments = segments.size();
    s.merge_triangles = all.size();
    return OrderedRuns(std::move(all));
  }
  const auto t_tiles = Clock::now();
  // The tiles' staging, allocated beside the plan (if the caller has not yet), again after it if a tile is larger.
  const uint64_t reserved = level == 1 && options.reserve ? tile_staging_points(n, options.max_tile_points) : 0;
  if (reserved) options.reserve(reserved);
  // Slabs only for a device's tiles: the CPU's merge is one core's CGAL run, where a slab's longer border costs
  // more than the selection it saves.
  const TileShape shape =
      options.shape == TileShape::automatic && !options.finalize ? TileShape::squares : options.shape;
  if (options.unresolved && !options.finalize)
    throw std::logic_error("tiled_cdt: an unresolved input needs a finalizer that checks its tiles");
  Plan plan = plan_tiles(v, options.max_tile_points, shape, options.ramp);
  const size_t tiles = plan.tiles.size();
  if (reserved) {
    uint64_t largest = 0;
    for (uint32_t t : plan.tiles) largest = std::max<uint64_t>(largest, plan.nodes[t].hi - plan.nodes[t].lo);
    if (staging_room(largest) > reserved) options.reserve(staging_room(largest));
  }
  const auto t_segments = Clock::now();
  TileSegments tile_segments_of = tile_segments(v, segments, plan);

  s.plan_ms += ms_since(t_tiles);
  spdlog::debug("tiles, level {}: {} {} of at most {} points planned in {:.0f} ms (their segments {:.0f} ms)", level,
                tiles, plan.slabs ? "slabs" : "tiles", options.max_tile_points, ms_since(t_tiles),
                ms_since(t_segments));
  // The final region's vertex marks, a byte a vertex zeroed on all cores (1 GB at 1B points): beside the first
  // tiles, which need them only once their CDT is done. The output too, where the machine has three times its
  // size free (the runs take as much again): touching its 24 GB at 1B points in the canonical order took ~0.4 s
  // on the 2 x H200 host, and beside the tiles it takes only a quarter of the cores that wait for the devices.
  std::vector<uint8_t> in_final;
  RunMerge order;
  const uint64_t available = host_memory().available, room_bytes = 2 * n * sizeof(Triangle);
  // Only slabs' runs are left: they interleave along the cuts only, so a chunk is mostly one span; square tiles'
  // interleave everywhere (ids run in x across a row of tiles): at 1B points in 20 tiles, 420M spans in 5.5 s,
  // where the copy takes ~0.3 s (session 64).
  const bool leave = options.in_runs && level == 1 && plan.slabs;
  const bool room = !leave && available / 3 > room_bytes;
  spdlog::debug("tiles, level {}: the output ({:.1f} GB) {} ahead, {:.1f} GB available", level, room_bytes / 1e9,
                leave ? "left in the tiles' runs, not made" : room ? "made" : "not made", available / 1e9);
  if (room) order.make_room(2 * n, std::thread::hardware_concurrency() / 4);
  const std::shared_future<void> bookkeeping =
      std::async(std::launch::async, [&] { resize_touched(in_final, n); }).share();
  std::vector<TileResult> results(tiles);
  auto tile_name = [&](size_t t) {
    return "tile " + std::to_string(t + 1) + " of " + std::to_string(tiles) + ", level " + std::to_string(level);
  };
  // Isolated: a thread waiting in a tile's own parallel loops takes no other tile (whose GPU call would make it
  // wait for the device as well).
  auto gather = [&](size_t t) {
    RawVector<uint32_t> scratch;
    const std::span<const uint32_t> its_segments = tile_segments_of.of(t, scratch);
    return tbb::this_task_arena::isolate(
        [&] { return gather_tile(segments, plan, plan.nodes[plan.tiles[t]], its_segments); });
  };
  auto finish = [&](size_t t, GatheredTile g) {
    const std::string name = tile_name(t);
    tbb::this_task_arena::isolate([&] {
      results[t] = finish_tile(v, std::move(g), plan.nodes[plan.tiles[t]], triangulate, options.finalize, name,
                               in_final, bookkeeping, level == 1 && options.unresolved, plan.slabs);
    });
    const TileResult& r = results[t];
    spdlog::debug("{}: {} final triangles; gather {:.0f} ms, CDT {:.0f} ms, the rest {:.0f} ms; done at {:.0f} ms",
                  name, r.final_triangles.size(), r.gather_ms, r.cdt_ms, r.other_ms - r.gather_ms,
                  ms_since(t_tiles));
  };
  // A tile that throws stops the tiles not yet begun, and the others in flight finish whole. Thrown through TBB,
  // the error cancelled those tiles' own parallel loops halfway: at 1B points a tile then ran its GPU call on
  // half-written input for 4.7 s before it failed too.
  std::exception_ptr failed;
  std::mutex failed_mutex;
  std::atomic<bool> stop{false};
  auto caught = [&](auto&& work) {
    if (stop.load()) return;
    try {
      work();
    } catch (...) {
      std::lock_guard<std::mutex> lock(failed_mutex);
      if (!failed) failed = std::current_exception();
      stop = true;
    }
  };
  auto run_tiles = [&] {
    if (options.tiles_in_flight == 0 || options.tiles_in_flight >= tiles) {
      tbb::parallel_for(size_t(0), tiles, size_t(1), [&](size_t t) { caught([&] { finish(t, gather(t)); }); });
    } else {
      // tiles_in_flight tiles on the devices, one more gathered: tiles are gathered one at a time, in order, on
      // every core, so the next tile is ready when a device is free (gathered beside the tiles' own finishing,
      // a tile's gather took as long as its GPU call and the device waited).
      std::vector<GatheredTile> gathered(tiles);
      size_t next = 0;
      tbb::parallel_pipeline(
          options.tiles_in_flight + 1,
          tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                         [&](tbb::flow_control& fc) -> size_t {
                                           if (next == tiles || stop.load()) fc.stop();
                                           return next < tiles ? next++ : 0;
                                         }) &
              tbb::make_filter<size_t, size_t>(tbb::filter_mode::serial_in_order,
                                               [&](size_t t) {
                                                 caught([&] { gathered[t] = gather(t); });
                                                 return t;
                                               }) &
              tbb::make_filter<size_t, void>(tbb::filter_mode::parallel, [&](size_t t) {
                caught([&] { finish(t, std::move(gathered[t])); });
              }));
    }
  };
  if (options.waiting_threads > 0) {
    // TBB's workers are as many as the cores unless told otherwise: the arena alone would not get the threads.
    const int threads = tbb::this_task_arena::max_concurrency() + int(options.waiting_threads);
    tbb::global_control more(tbb::global_control::max_allowed_parallelism, size_t(threads));
    tbb::task_arena wider(threads);
    wider.execute(run_tiles);
  } else {
    run_tiles();
  }
  if (failed) std::rethrow_exception(failed);
  if (level == 1 && options.tiles_done) options.tiles_done();
  bookkeeping.get();  // its error, if any

  const double tiles_wall_ms = ms_since(t_tiles);
  // The merge's input (merge_job). What only the tiles read is freed beside it, long before the canonical order's
  // peak (6 GB of it at 1B points + 250M segments).
  const auto t_merge_input = Clock::now();
  std::future<void> tiles_input_freed =
      std::async(std::launch::async, [order = std::move(plan.order), ids = std::move(tile_segments_of.ids)]() mutable {
        free_storage_on_all_cores(order);
        free_storage_on_all_cores(ids);
      });
  std::vector<Triangles> runs(tiles);
  std::vector<std::array<uint32_t, 3>> split;
  uint64_t final_count = 0;
  for (size_t t = 0; t < tiles; ++t) {
    split.insert(split.end(), results[t].split.begin(), results[t].split.end());
    s.tile_cdt_thread_ms += results[t].cdt_ms;
    s.tile_other_thread_ms += results[t].other_ms;
    s.tile_gather_thread_ms += results[t].gather_ms;
    s.tile_final_thread_ms += results[t].final_ms;
    final_count += results[t].final_triangles.size();
    runs[t] = std::move(results[t].final_triangles);
  }
  // The tiles' borders, and the slabs' merge vertices in id order, joined on all cores: appended on one core (6.2M
  // border edges and 5.9M ids at 100M points + 25M contour vertices in tiles of 20M), with the frees before them,
  // taking the tiles' results took 85-148 ms on the 2 x H200 host, now 18-19.
  std::vector<size_t> in_order(tiles);
  std::iota(in_order.begin(), in_order.end(), size_t(0));
  const std::vector<Edge> border = joined<Edge>(in_order, [&](size_t t) -> const auto& { return results[t].border; });
  std::vector<uint32_t> slab_ids;
  if (plan.slabs) {
    std::sort(in_order.begin(), in_order.end(),
              [&](size_t a, size_t b) { return plan.nodes[plan.tiles[a]].lo < plan.nodes[plan.tiles[b]].lo; });
    slab_ids = joined<uint32_t>(in_order, [&](size_t t) -> const auto& { return results[t].merge_ids; });
  }
  results.clear();
  // Segments the tiles split at vertices: the merge takes their pieces, as the resolve would have split them.
  VertexSplits split_segments;
  if (!split.empty()) {
    split_segments = split_at_vertices(v, segments, std::move(split));
    s.split_at_vertices += split_segments.splits;
    spdlog::debug("tiles, level {}: {} segments split at {} vertices", level, split_segments.split.size(),
                  split_segments.splits);
  }
  const double taken_ms = ms_since(t_merge_input);
  const MergeJob m = merge_job(v, segments, border, split_segments, in_final, plan.slabs, std::move(slab_ids));
  s.tiles += tiles;
  s.levels += 1;
  if (level == 1) s.final_triangles = final_count;
  s.merge_input_ms += ms_since(t_merge_input);
  s.tiles_ms += ms_since(t_tiles);

  spdlog::debug("tiles, level {}: tiles done at {:.0f} ms, their results taken in {:.0f} ms, the merge's input ({} "
                "vertices) at {:.0f} ms",
                level, tiles_wall_ms, taken_ms, m.ids.size(), ms_since(t_tiles));
  // Tiled again while that shrinks it; the last level is one call (its time is merge_ms).
  const bool again =
      m.ids.size() > options.max_tile_points && double(m.ids.size()) <= options.retile_share * double(n);
  Triangles merged;
  if (again) {
    merged = tiled_runs(m.vertices, m.segments, options, triangulate, s).take();
  } else {
    const auto t = Clock::now();
    merged = triangulate(m.vertices, m.segments, "merge, level " + std::to_string(level)).triangles;
    canonicalize_triangles(merged);
    s.merge_ms = ms_since(t);
    s.merge_vertices = m.ids.size();
    s.merge_segments = m.segments.size();
  }
  const auto t_keep = Clock::now();
  Triangles kept = outside_final(merged, uint32_t(m.ids.size()), m.border);  // in order: still a sorted run
  if (!again) s.merge_triangles = kept.size();
  tbb::parallel_for(size_t(0), kept.size(), [&](size_t i) {
    for (uint32_t& id : kept[i]) id = m.ids[id];
  });
  runs.push_back(std::move(kept));
  const double keep_ms = ms_since(t_keep);
  s.tiles_ms += keep_ms;
  s.keep_ms += keep_ms;
  const auto t_order = Clock::now();
  OrderedRuns out = leave ? order.in_place(std::move(runs)) : OrderedRuns(order.merge(runs));
  const double order_ms = ms_since(t_order);
  s.order_ms += order_ms;
  spdlog::debug("tiles, level {}: the merge's triangles kept in {:.0f} ms, canonical order {}in {:.0f} ms", level,
                keep_ms, leave ? "left in the runs " : "", order_ms);
  return out;
}

}  // namespace

OrderedRuns tiled_cdt_runs(const Points& v, const std::vector<Edge>& segments, const TileOptions& options,
                           const TileTriangulator& triangulate, TileStats* stats) {
  TileStats local_stats;
  return tiled_runs(v, segments, options, triangulate, stats ? *stats : local_stats);
}

Triangles tiled_cdt(const Points& v, const std::vector<Edge>& segments,
                                const TileOptions& options, const TileTriangulator& triangulate,
                                TileStats* stats) {
  return tiled_cdt_runs(v, segments, options, triangulate, stats).take();
}

CdtResult triangulate_tiled(ResolvedInput&& in, const TileOptions& options,
                            const TileTriangulator& triangulate, TileStats* stats) {
  CdtResult r;
  r.steiner_points = in.steiner_points;
  OrderedRuns t = tiled_cdt_runs(in.vertices, in.constraints, options, triangulate, stats);
  if (options.in_runs)
    r.in_runs = std::move(t);
  else
    r.mesh.triangles = std::move(t).take();
  r.mesh.vertices =
      std::move(in.vertices);  // sorted and unique already: the triangles are in canonical order
  return r;
}

std::vector<MeshPiece> split_mesh(const Mesh& mesh, uint64_t tile_points) {
  const Points& v = mesh.vertices;
  if (v.empty()) return {};
  const Plan plan = plan_tiles(v, std::max<uint64_t>(1, tile_points));
  const size_t tiles = plan.tiles.size();
  std::vector<uint32_t> owner(v.size(), 0);
  for (size_t t = 0; t < tiles; ++t) {
    const Node& node = plan.nodes[plan.tiles[t]];
    for (uint32_t i = node.lo; i < node.hi; ++i) owner[plan.id_at(i)] = uint32_t(t);
  }
  std::vector<uint8_t> used(v.size(), 0);
  std::vector<std::vector<uint32_t>> triangles_of(tiles);  // canonical order kept: the mesh's is
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    triangles_of[owner[mesh.triangles[i][0]]].push_back(uint32_t(i));
    for (uint32_t id : mesh.triangles[i]) used[id] = 1;
  }
  std::vector<MeshPiece> pieces(tiles);
  tbb::parallel_for(size_t(0), tiles, [&](size_t t) {
    const Node& node = plan.nodes[plan.tiles[t]];
    std::vector<uint32_t> ids;
    for (uint32_t i = node.lo; i < node.hi; ++i)
      if (!used[plan.id_at(i)]) ids.push_back(plan.id_at(i));
    for (uint32_t i : triangles_of[t])
      for (uint32_t id : mesh.triangles[i]) ids.push_back(id);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    MeshPiece& p = pieces[t];
    p.x0 = p.y0 = kInf;
    p.x1 = p.y1 = -kInf;
    for (uint32_t id : ids) {
      p.mesh.vertices.push_back(v[id]);
      p.x0 = std::min(p.x0, v[id].x), p.x1 = std::max(p.x1, v[id].x);
      p.y0 = std::min(p.y0, v[id].y), p.y1 = std::max(p.y1, v[id].y);
    }
    auto local = [&](uint32_t id) {
      return uint32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
    };
    for (uint32_t i : triangles_of[t]) {
      const Triangle& g = mesh.triangles[i];
      p.mesh.triangles.push_back({local(g[0]), local(g[1]), local(g[2])});
    }
  });
  return pieces;
}

bool circumdisk_inside(const Point3& a, const Point3& b, const Point3& c, double x0, double x1, double y0,
                       double y1) {
  return disk_inside(a, b, c, Rect{x0, x1, y0, y1});
}

uint64_t tile_staging_points(uint64_t n, uint64_t max_tile_points) {
  const uint64_t tiles = (n + max_tile_points - 1) / max_tile_points;
  return staging_room((n + tiles - 1) / tiles);
}

uint64_t auto_cpu_tile_points(uint64_t vertices, unsigned cores) {
  // At most 1M points: CGAL takes 1.34 us a point in tiles of 1M against 1.79 in tiles of 2M (16M points on 2
  // cores: 16.6 s against 21.3 s, the merge 279 against 194 ms), and the tiles in flight hold cores x 1M points
  // in CGAL's structures instead of a quarter of the input.
  constexpr uint64_t kMinPoints = 100'000, kMinTile = 20'000, kMaxTile = 1'000'000;
  if (cores < 2 || vertices < kMinPoints) return 0;
  // Rounded up: rounded down, 64 tiles asked of 2.5M vertices came as 80 (a column of 312,589 vertices is
  // more than 8 tiles of 39,073), five rounds on 16 cores instead of four.
  return std::clamp((vertices + 4 * uint64_t(cores) - 1) / (4 * uint64_t(cores)), kMinTile, kMaxTile);
}

uint64_t auto_gpu_tile_points(uint64_t vertices, uint64_t device_max, size_t devices) {
  const uint64_t d = std::max<uint64_t>(devices, 1);
  const uint64_t quarter = std::min(device_max, vertices / (4 * d) + 1);
  if (d == 1) return quarter;
  constexpr uint64_t kLeast = uint64_t(1) << 25;  // the smallest measured to pay (39M at 1B on two H200s)
  return std::min(quarter, std::max({vertices / (12 * d) + 1, kLeast, vertices / 64 + 1}));
}

}  // namespace cdtgpu
