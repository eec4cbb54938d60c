// merge_points on the CPU: a bucket sort by x on all cores, then the duplicates numbered on all cores.
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

#include <algorithm>
#include <cmath>
#include <execution>
#include <limits>
#include <memory>
#include <utility>

namespace cdtgpu {
namespace {

struct Occurrence {
  double x, y;
  uint32_t occ;  // index of the point in the input
};

bool xy_less(const Occurrence& a, const Occurrence& b) {
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

Buckets buckets_for(std::span<const double> xy, size_t n) {
  using Range = std::pair<double, double>;
  const double inf = std::numeric_limits<double>::infinity();
  const Range r = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, kBlock), Range{inf, -inf},
      [&](const tbb::blocked_range<size_t>& b, Range m) {
        for (size_t i = b.begin(); i < b.end(); ++i) m = {std::min(m.first, xy[2 * i]), std::max(m.second, xy[2 * i])};
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

// Sorts [first, last) by xy_less; a crowded range (all x equal, say) on all cores.
void sort_range(Occurrence* first, Occurrence* last, size_t n) {
  if (size_t(last - first) > std::max<size_t>(n / 64, kBlock))
    std::sort(std::execution::par, first, last, xy_less);
  else
    std::sort(first, last, xy_less);
}

}  // namespace

PointMerge merge_points(std::span<const double> xy) {
  const size_t n = xy.size() / 2;
  PointMerge m;
  if (n == 0) return m;
  const Buckets bk = buckets_for(xy, n);

  // Pass 1, per block of points: a histogram of coarse buckets. Pass 2: each block writes its points to their
  // places (bucket-major, blocks in order): no atomics, and each block's stores go to `coarse` streams. Blocks
  // grow with n so that the histograms stay ~4096 rows (1B points in blocks of 32K made 500 MB of them).
  const size_t block = std::max(kBlock, n / 4096 + 1);
  const size_t blocks = (n + block - 1) / block;
  std::vector<uint32_t> place(blocks * bk.coarse, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* h = &place[b * bk.coarse];
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) ++h[bk.of(xy[2 * i]) >> bk.shift];
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
  RawVector<Occurrence> occ;
  resize_unwritten(occ, n);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* at = &place[b * bk.coarse];
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
      occ[at[bk.of(xy[2 * i]) >> bk.shift]++] = {xy[2 * i], xy[2 * i + 1], uint32_t(i)};
  });
  // Per coarse bucket, in cache: a counting sort by fine bucket into a buffer of the thread's, each fine bucket
  // sorted there, and the bucket copied back.
  tbb::enumerable_thread_specific<std::vector<Occurrence>> buffers;
  tbb::parallel_for(uint32_t(0), bk.coarse, [&](uint32_t c) {
    const uint32_t begin = coarse_start[c], end = coarse_start[c + 1];
    const uint32_t mask = (1u << bk.shift) - 1;
    std::vector<Occurrence>& sorted = buffers.local();
    sorted.resize(std::max<size_t>(sorted.size(), end - begin));
    std::vector<uint32_t> fine_start((size_t(1) << bk.shift) + 1, 0);
    for (uint32_t i = begin; i < end; ++i) ++fine_start[(bk.of(occ[i].x) & mask) + 1];
    for (size_t f = 1; f < fine_start.size(); ++f) fine_start[f] += fine_start[f - 1];
    std::vector<uint32_t> at(fine_start.begin(), fine_start.end() - 1);
    for (uint32_t i = begin; i < end; ++i) sorted[at[bk.of(occ[i].x) & mask]++] = occ[i];
    for (size_t f = 0; f + 1 < fine_start.size(); ++f)
      if (fine_start[f + 1] - fine_start[f] > 1) sort_range(&sorted[fine_start[f]], &sorted[fine_start[f + 1]], n);
    std::copy(sorted.begin(), sorted.begin() + (end - begin), occ.begin() + begin);
  });

  // Vertex numbers: a new vertex where (x, y) changes; blocks count their heads, a scan gives each block its
  // first number.
  auto head = [&](size_t i) { return i == 0 || occ[i].x != occ[i - 1].x || occ[i].y != occ[i - 1].y; };
  const size_t runs = (n + kBlock - 1) / kBlock;
  std::vector<uint32_t> heads(runs + 1, 0);
  tbb::parallel_for(size_t(0), runs, [&](size_t k) {
    uint32_t c = 0;
    for (size_t i = k * kBlock; i < std::min(n, (k + 1) * kBlock); ++i) c += head(i);
    heads[k + 1] = c;
  });
  for (size_t k = 1; k <= runs; ++k) heads[k] += heads[k - 1];
  resize_unwritten(m.vertex_of, n);  // every element written below, on all cores
  resize_unwritten(m.first, heads[runs]);
  tbb::parallel_for(size_t(0), runs, [&](size_t k) {
    uint32_t v = heads[k];
    for (size_t i = k * kBlock; i < std::min(n, (k + 1) * kBlock); ++i) {
      if (head(i)) m.first[v++] = occ[i].occ;
      m.vertex_of[occ[i].occ] = v - 1;
    }
  });
  return m;
}

}  // namespace cdtgpu
