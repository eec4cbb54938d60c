// merge_points and merge_input on the CPU: a bucket sort by x on all cores, then the duplicates numbered on all
// cores.
// Why not one std::sort(par) of every point: it took ~150 ms for 2.5M points on the H100 machine's 16 cores
// and 230 ms on 2; a bucket pass plus small sorts that stay in cache take 31-44 ms and 77 ms
// (docs/performance.md). Inside a bucket the order is the comparator's, so the result is the same whatever the
// split.
#include "core/prepare.hpp"
#include "core/touched.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <execution>
#include <limits>
#include <functional>
#include <memory>
#include <string>
#include <utility>

namespace cdtgpu {
namespace {

struct Occurrence {
  double x, y;
  uint32_t occ;  // index of the point in the input
};

// prepare's own merge carries z along: the merged vertices and their z conflicts then come out of the sorted
// array in order, where gathering them by index was two random reads a point (6.3 s of prepare's 27.6 at 1B
// points on 16 threads).
struct OccurrenceZ {
  double x, y, z;
  uint32_t occ;
};

template <class Occ>
bool xy_less(const Occ& a, const Occ& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.occ < b.occ;  // the first occurrence leads its group
}

constexpr size_t kBlock = size_t(1) << 15;  // points per task in the linear passes

// The sort key of x: its fine bucket floor((x - lo) * scale), clamped. Rounding is monotonic, so x1 < x2 never
// puts x2 in an earlier bucket, and equal x (-0.0 and +0.0 included) share one; sorting by bucket, then by
// (x, y, occ) inside buckets, sorts by (x, y, occ). Coarse buckets (the top bits) split the points between
// tasks; fine ones (the low `shift` bits) split a coarse bucket in cache.
struct Buckets {
  double lo = 0, scale = 0;
  uint32_t fine = 1, coarse = 1, shift = 0;
  uint32_t of(double x) const {
    const double b = (x - lo) * scale;
    return b >= double(fine - 1) ? fine - 1 : b > 0 ? uint32_t(b) : 0u;
  }
};

// `each(begin, end, f)` calls f(i, x, y, z) for the points i in [begin, end), in order.
template <class Each>
Buckets buckets_for(const Each& each, size_t n) {
  using Range = std::pair<double, double>;
  const double inf = std::numeric_limits<double>::infinity();
  const Range r = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, kBlock), Range{inf, -inf},
      [&](const tbb::blocked_range<size_t>& b, Range m) {
        each(b.begin(), b.end(), [&](size_t, double x, double, double) {
          m = {std::min(m.first, x), std::max(m.second, x)};
        });
        return m;
      },
      [](Range a, Range b) { return Range{std::min(a.first, b.first), std::max(a.second, b.second)}; });
  Buckets k;
  const double width = r.second - r.first;
  // About 8 points per fine bucket on even data. A zero or overflowing x range (every point on one vertical
  // line, or coordinates near the double limit) gives one bucket, sorted on all cores below.
  if (n < 64 || !(width > 0) || !std::isfinite(width)) return k;
  while (k.fine < n / 8 && k.fine < (1u << 28)) k.fine <<= 1;
  k.coarse = std::min(k.fine, 4096u);
  while ((k.coarse << k.shift) < k.fine) ++k.shift;
  k.lo = r.first;
  k.scale = double(k.fine) / width;
  return k;
}

template <class Occ>
bool is_head(const RawVector<Occ>& occ, size_t i) {
  return i == 0 || occ[i].x != occ[i - 1].x || occ[i].y != occ[i - 1].y;
}

// Sorts [first, last) by xy_less; a crowded range (all x equal, say) on all cores.
template <class Occ>
void sort_range(Occ* first, Occ* last, size_t n) {
  if (size_t(last - first) > std::max<size_t>(n / 64, kBlock))
    std::sort(std::execution::par, first, last, xy_less<Occ>);
  else
    std::sort(first, last, xy_less<Occ>);
}

// Every point's occurrence sorted by (x, y, occ) into `occ`: a bucket sort by x on all cores. `make(x, y, z, i)`
// makes an occurrence; `scattered`, if given, is called once `each` is read no more.
template <class Occ, class Each, class Make>
void sort_occurrences(const Each& each, size_t n, const Make& make, RawVector<Occ>& occ,
                      const std::function<void()>& scattered = {}) {
  const Buckets bk = buckets_for(each, n);

  // Pass 1, per block of points: a histogram of coarse buckets. Pass 2: each block writes its points to their
  // places (bucket-major, blocks in order): no atomics, and each block's stores go to `coarse` streams. Blocks
  // grow with n so that the histograms stay ~4096 rows (1B points in blocks of 32K made 500 MB of them).
  const size_t block = std::max(kBlock, n / 4096 + 1);
  const size_t blocks = (n + block - 1) / block;
  std::vector<uint32_t> place(blocks * bk.coarse, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* h = &place[b * bk.coarse];
    each(b * block, std::min(n, (b + 1) * block), [&](size_t, double x, double, double) { ++h[bk.of(x) >> bk.shift]; });
  });
  // Bucket starts from the column totals, then each block's places from the running starts: both walk `place`
  // row by row (column by column, 64M points were 8M cache misses).
  std::vector<uint32_t> coarse_start(size_t(bk.coarse) + 1, 0);
  for (size_t b = 0; b < blocks; ++b)
    for (uint32_t c = 0; c < bk.coarse; ++c) coarse_start[c + 1] += place[b * bk.coarse + c];
  for (uint32_t c = 0; c < bk.coarse; ++c) coarse_start[c + 1] += coarse_start[c];
  std::vector<uint32_t> running(coarse_start.begin(), coarse_start.end() - 1);
  for (size_t b = 0; b < blocks; ++b)
    for (uint32_t c = 0; c < bk.coarse; ++c) running[c] += std::exchange(place[b * bk.coarse + c], running[c]);
  // The points themselves are scattered, not their indices: a coarse bucket is then read front to back (with
  // indices, each of its points was a random read of xy, ~25 s at 1B points on 16 threads). Unzeroed storage:
  // the scatter touches its pages first, on all cores.
  resize_unwritten(occ, n);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* at = &place[b * bk.coarse];
    each(b * block, std::min(n, (b + 1) * block), [&](size_t i, double x, double y, double z) {
      occ[at[bk.of(x) >> bk.shift]++] = make(x, y, z, uint32_t(i));
    });
  });
  if (scattered) scattered();
  // Per coarse bucket, in cache: a counting sort by fine bucket into a buffer of the thread's, each fine bucket
  // sorted there, and the bucket copied back. The counts are the thread's too, not allocated per bucket (4096
  // buckets of 65536 fine ones at 1B points: 8192 allocations of 256 KB).
  struct Scratch {
    std::vector<Occ> sorted;
    std::vector<uint32_t> fine_start, at;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(uint32_t(0), bk.coarse, [&](uint32_t c) {
    const uint32_t begin = coarse_start[c], end = coarse_start[c + 1];
    const uint32_t mask = (1u << bk.shift) - 1;
    Scratch& local = scratch.local();
    std::vector<Occ>& sorted = local.sorted;
    sorted.resize(std::max<size_t>(sorted.size(), end - begin));
    std::vector<uint32_t>& fine_start = local.fine_start;
    fine_start.assign((size_t(1) << bk.shift) + 1, 0);
    for (uint32_t i = begin; i < end; ++i) ++fine_start[(bk.of(occ[i].x) & mask) + 1];
    for (size_t f = 1; f < fine_start.size(); ++f) fine_start[f] += fine_start[f - 1];
    std::vector<uint32_t>& at = local.at;
    at.assign(fine_start.begin(), fine_start.end() - 1);
    for (uint32_t i = begin; i < end; ++i) sorted[at[bk.of(occ[i].x) & mask]++] = occ[i];
    for (size_t f = 0; f + 1 < fine_start.size(); ++f)
      if (fine_start[f + 1] - fine_start[f] > 1) sort_range(&sorted[fine_start[f]], &sorted[fine_start[f + 1]], n);
    std::copy(sorted.begin(), sorted.begin() + (end - begin), occ.begin() + begin);
  });
}

// Vertex numbers: a new vertex where (x, y) changes. Blocks count their heads; heads[k] is then block k's first
// vertex, heads.back() the count.
template <class Occ>
std::vector<uint32_t> count_heads(const RawVector<Occ>& occ) {
  const size_t n = occ.size(), runs = (n + kBlock - 1) / kBlock;
  std::vector<uint32_t> heads(runs + 1, 0);
  tbb::parallel_for(size_t(0), runs, [&](size_t k) {
    uint32_t c = 0;
    for (size_t i = k * kBlock; i < std::min(n, (k + 1) * kBlock); ++i) c += is_head(occ, i);
    heads[k + 1] = c;
  });
  for (size_t k = 1; k <= runs; ++k) heads[k] += heads[k - 1];
  return heads;
}

}  // namespace

PointMerge merge_points(std::span<const double> xy) {
  const size_t n = xy.size() / 2;
  PointMerge m;
  if (n == 0) return m;
  auto each = [&](size_t begin, size_t end, const auto& f) {
    for (size_t i = begin; i < end; ++i) f(i, xy[2 * i], xy[2 * i + 1], 0.0);
  };
  RawVector<Occurrence> occ;
  sort_occurrences(each, n, [](double x, double y, double, uint32_t i) { return Occurrence{x, y, i}; }, occ);
  const std::vector<uint32_t> heads = count_heads(occ);
  const size_t runs = heads.size() - 1;
  resize_unwritten(m.vertex_of, n);  // every element written below, on all cores
  resize_unwritten(m.first, heads[runs]);
  tbb::parallel_for(size_t(0), runs, [&](size_t k) {
    uint32_t v = heads[k];
    for (size_t i = k * kBlock; i < std::min(n, (k + 1) * kBlock); ++i) {
      if (is_head(occ, i)) m.first[v++] = occ[i].occ;
      m.vertex_of[occ[i].occ] = v - 1;
    }
  });
  return m;
}

MergedInput merge_input(const InputSet& in, const std::function<void()>& scattered) {
  using Clock = std::chrono::steady_clock;
  // Loose points' vertices are not kept (only lines make segments). Taken now: `scattered` may free them.
  const uint64_t loose = in.points.size();
  // The occurrences in prepare's order, as runs of points: the loose points, then each line's.
  std::vector<const Point3*> part;
  std::vector<uint64_t> starts;
  uint64_t n = 0;
  auto add = [&](const Points& p) {
    if (p.empty()) return;
    part.push_back(p.data());
    starts.push_back(n);
    n += p.size();
  };
  add(in.points);
  for (const Polyline& l : in.lines) add(l.points);
  starts.push_back(n);
  std::atomic<bool> bad{false};
  auto each = [&](size_t begin, size_t end, const auto& f) {
    size_t k = size_t(std::upper_bound(starts.begin(), starts.end(), begin) - starts.begin()) - 1;
    bool finite = true;
    for (size_t i = begin; i < end; ++k) {
      const Point3* p = part[k];
      const size_t from = starts[k], stop = std::min<uint64_t>(end, starts[k + 1]);
      for (; i < stop; ++i) {
        const Point3& q = p[i - from];
        finite &= std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
        f(i, q.x, q.y, q.z);
      }
    }
    if (!finite) bad.store(true, std::memory_order_relaxed);
  };
  MergedInput out;
  if (n == 0) return out;
  RawVector<OccurrenceZ> occ;
  const auto make = [](double x, double y, double z, uint32_t i) { return OccurrenceZ{x, y, z, i}; };
  auto t = Clock::now();
  double scatter_ms = 0, freed_ms = 0;
  sort_occurrences(each, n, make, occ, [&] {
    // NaN would break the sort's strict weak order; readers reject it, this guards direct callers.
    if (bad)
      for (uint64_t i = 0; i < n; ++i)
        each(i, i + 1, [&](size_t, double x, double y, double z) {
          if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
            throw std::invalid_argument("prepare: vertex " + std::to_string(i) + " is not finite");
        });
    scatter_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    t = Clock::now();
    if (scattered) scattered();
    freed_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    t = Clock::now();
  });
  const double sort_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  t = Clock::now();

  // The vertices in order: each group's head is its first occurrence (xy_less), whose coordinates and z it
  // keeps; a later z that differs is a conflict of that vertex.
  const std::vector<uint32_t> heads = count_heads(occ);
  const size_t runs = heads.size() - 1;
  resize_unwritten(out.line_vertex_of, n - loose);
  resize_unwritten(out.vertices, heads[runs]);
  std::vector<double> largest(runs, 0);
  std::vector<std::vector<uint32_t>> conflicted(runs);
  tbb::parallel_for(size_t(0), runs, [&](size_t k) {
    const size_t first = k * kBlock, last = std::min<size_t>(n, first + kBlock);
    size_t h = first;
    while (!is_head(occ, h)) --h;  // a group begun in the block before
    double hz = occ[h].z;
    uint32_t v = heads[k];
    for (size_t i = first; i < last; ++i) {
      const OccurrenceZ& o = occ[i];
      if (is_head(occ, i)) {
        out.vertices[v++] = {o.x, o.y, o.z};
        hz = o.z;
      } else if (const double dz = std::abs(o.z - hz); dz != 0) {
        largest[k] = std::max(largest[k], dz);
        if (conflicted[k].empty() || conflicted[k].back() != v - 1) conflicted[k].push_back(v - 1);
      }
      if (o.occ >= loose) out.line_vertex_of[o.occ - loose] = v - 1;
    }
  });
  // Vertices ascend within a block and from block to block; one group may end a block and begin the next.
  int64_t last_conflict = -1;
  for (size_t k = 0; k < runs; ++k) {
    out.max_z_conflict = std::max(out.max_z_conflict, largest[k]);
    for (uint32_t v : conflicted[k])
      if (int64_t(v) != last_conflict) ++out.z_conflicts, last_conflict = v;
  }
  spdlog::debug("prepare: merge: scatter {:.1f} ms, the input's points freed {:.1f} ms, sort {:.1f} ms, vertices "
                "{:.1f} ms",
                scatter_ms, freed_ms, sort_ms, std::chrono::duration<double, std::milli>(Clock::now() - t).count());
  return out;
}

}  // namespace cdtgpu
