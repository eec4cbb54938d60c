// merge_points and merge_input on the CPU: a bucket sort by x on all cores, each bucket's vertices numbered and
// written as soon as it is sorted.
// Why not one std::sort(par) of every point: it took ~150 ms for 2.5M points on the H100 machine's 16 cores
// and 230 ms on 2; a bucket pass plus small sorts that stay in cache take 31-44 ms and 77 ms
// (docs/performance.md). Inside a bucket the order is the comparator's, so the result is the same whatever the
// split.
#include "core/counting_sort.hpp"
#include "core/prepare.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <execution>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>

namespace cdtgpu {
namespace {

struct Occurrence {
  double x, y;
  uint32_t occ;   // index of the point in the input
  uint32_t fine;  // its fine bucket within its coarse one, kept from the scatter (the padding's room)
};

// prepare's own merge carries z along: the merged vertices and their z conflicts then come out of the sorted
// array in order, where gathering them by index was two random reads a point (6.3 s of prepare's 27.6 at 1B
// points on 16 threads).
struct OccurrenceZ {
  double x, y, z;
  uint32_t occ, fine;
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
//
// The x range from a sample of up to 2^20 points spread over the input, less its outer 1/8192 on each side,
// instead of a pass over every point: that pass read the whole input once more (24 bytes a point), and one far
// outlier (a LiDAR noise point, a record at x = 0) stretched the range so that a few buckets held every point and
// the sort ran on a few cores. Points outside the range are clamped into the end buckets (sorted there like any
// other), so the result does not depend on the range.
template <class Each>
Buckets buckets_for(const Each& each, size_t n) {
  const size_t samples = std::min(n, size_t(1) << 20);
  std::vector<double> xs(samples);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const size_t i = uint64_t(k) * n / samples;
      each(i, i + 1, [&](size_t, double x, double, double) { xs[k] = x; });
    }
  });
  std::erase_if(xs, [](double x) { return !std::isfinite(x); });
  std::pair<double, double> r{0, 0};
  if (!xs.empty()) {
    const size_t trim = xs.size() >> 13;
    std::nth_element(xs.begin(), xs.begin() + trim, xs.end());
    r.first = xs[trim];
    std::nth_element(xs.begin() + trim, xs.end() - 1 - trim, xs.end());
    r.second = xs[xs.size() - 1 - trim];
  }
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
bool same_xy(const Occ& a, const Occ& b) {
  return a.x == b.x && a.y == b.y;
}

// Sorts a fine bucket's points [first, last) by xy_less in cache: more than 16 by buckets of their x (of their y
// where every x is equal), a quarter as many buckets as points, as the fine buckets were made, down to 16 or
// fewer, which std::sort takes. Quantized LiDAR, a grid DEM or contours cut at common x put tens to thousands of
// points on one x, where std::sort took 60-130 ns a point (28-34 with buckets; 100 and 8000 points on one x).
// A range the buckets do not split (far outliers, say) ends in std::sort after kLevels levels.
constexpr int kLevels = 8;
using LevelStarts = std::array<std::vector<uint32_t>, kLevels>;  // each level's bucket starts

template <class Occ>
void sort_small(Occ* first, Occ* last, std::vector<Occ>& tmp, LevelStarts& starts, int depth = 0) {
  const size_t g = size_t(last - first);
  if (g <= 16 || depth == kLevels) return std::sort(first, last, xy_less<Occ>);
  double x0 = first->x, x1 = x0, y0 = first->y, y1 = y0;
  for (const Occ* p = first + 1; p != last; ++p) {
    x0 = std::min(x0, p->x), x1 = std::max(x1, p->x);
    y0 = std::min(y0, p->y), y1 = std::max(y1, p->y);
  }
  const bool by_x = x0 != x1;
  const double lo = by_x ? x0 : y0, width = by_x ? x1 - x0 : y1 - y0;
  const uint32_t buckets = uint32_t(g / 4);
  const double scale = double(buckets) / width;
  // Every (x, y) equal (the order is then by occurrence), or a width the buckets cannot take.
  if (!(width > 0) || !std::isfinite(scale) || !(scale > 0)) return std::sort(first, last, xy_less<Occ>);
  auto bucket_of = [&](const Occ& o) {  // monotone: equal keys share a bucket
    const double b = ((by_x ? o.x : o.y) - lo) * scale;
    return b >= double(buckets - 1) ? buckets - 1 : uint32_t(b);
  };
  if (tmp.size() < g) tmp.resize(g);
  std::vector<uint32_t>& s = starts[depth];
  counting_sort(first, g, tmp.data(), buckets, bucket_of, s);
  std::copy(tmp.begin(), tmp.begin() + g, first);
  for (uint32_t b = 0; b < buckets; ++b)
    if (s[b + 1] - s[b] > 1) sort_small(first + s[b], first + s[b + 1], tmp, starts, depth + 1);
}

// Sorts [first, last) by xy_less; a crowded range (all x equal, say) on all cores.
template <class Occ>
void sort_range(Occ* first, Occ* last, size_t n, std::vector<Occ>& tmp, LevelStarts& starts) {
  if (size_t(last - first) > std::max<size_t>(n / 64, kBlock))
    std::sort(std::execution::par, first, last, xy_less<Occ>);
  else
    sort_small(first, last, tmp, starts);
}

// Every point's occurrence sorted by (x, y, occ), a bucket at a time, each bucket handed to `emit(sorted,
// first_vertex)` (on all cores, in no order) with the number of its first vertex: vertices are numbered
// in (x, y) order, a new one where (x, y) changes. Returns the vertex count. A bucket sort by x: `make(x, y, z, i)`
// makes an occurrence; `scattered`, if given, is called once `each` is read no more.
template <class Occ, class Each, class Make, class Emit>
uint32_t sort_occurrences(const Each& each, size_t n, const Make& make, const Emit& emit,
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
  // indices, each of its points was a random read of xy, ~25 s at 1B points on 16 threads). Each keeps its fine
  // bucket in the padding. Unzeroed storage: the scatter touches its pages first, on all cores.
  RawVector<Occ> occ;
  resize_unwritten(occ, n);
  const uint32_t mask = (1u << bk.shift) - 1;
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* at = &place[b * bk.coarse];
    each(b * block, std::min(n, (b + 1) * block), [&](size_t i, double x, double y, double z) {
      const uint32_t f = bk.of(x);
      Occ& o = occ[at[f >> bk.shift]++];
      o = make(x, y, z, uint32_t(i));
      o.fine = f & mask;
    });
  });
  if (scattered) scattered();

  // Per coarse bucket, in cache: a counting sort by fine bucket into a buffer of the thread's, each fine bucket
  // sorted there, and the heads counted. The bucket's first vertex is the heads of the buckets before it: the
  // workers take buckets in order, each publishes its count, then looks back over those before it until one
  // knows its whole prefix (a decoupled look-back). Once every bucket before it is counted, the bucket is emitted
  // from the buffer and its pages of `occ` given back. Until then its worker holds it and sorts the next (three
  // buffers a worker); only a bucket that would need a fourth is written back and emitted after the sort. Nobody
  // waits: with waits, one slow bucket (its worker descheduled beside the driver's threads) held every worker
  // after it, 20-28 % of the workers' time at 1B points on 32 threads; with one buffer, 55-82 % of the buckets
  // were written back; with three, 15-42 of 4096. Before, the sorted occurrences were copied back, counted and
  // read again by a vertex pass: 4 of 7 passes over 32 bytes a point (docs/performance.md, session 64). Equal x
  // share a fine bucket, so a group of equal (x, y) never spans two buckets. The counts are the thread's, not
  // allocated per bucket (4096 buckets of 65536 fine ones at 1B points: 8192 allocations of 256 KB).
  constexpr uint64_t kCounted = uint64_t(1) << 62, kPrefixed = uint64_t(1) << 63, kValue = kCounted - 1;
  constexpr size_t kHeld = 3;                            // sorted buckets a worker may hold
  std::vector<std::atomic<uint64_t>> state(bk.coarse);  // 0, kCounted | heads, or kPrefixed | heads up to it
  std::vector<uint32_t> count(bk.coarse, 0);             // each bucket's heads
  std::vector<uint8_t> later(bk.coarse, 0);              // written back, to be emitted from `occ`
  std::atomic<uint32_t> next{0};
  struct Held {
    uint32_t bucket;
    std::vector<Occ>* sorted;
  };
  struct Scratch {
    std::array<std::vector<Occ>, kHeld> buffers;
    std::vector<Held> held;  // by bucket
    std::vector<uint32_t> fine_start;
    LevelStarts starts;    // sort_small's
    std::vector<Occ> tmp;  // sort_small's
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  // The vertices before `c` if every bucket before it is counted (walking back to one that knows its prefix).
  auto prefix = [&](uint32_t c) -> std::optional<uint64_t> {
    uint64_t before = 0;
    for (uint32_t j = c; j-- > 0;) {
      const uint64_t s = state[j].load(std::memory_order_acquire);
      if (s == 0) return std::nullopt;
      before += s & kValue;
      if (s & kPrefixed) break;
    }
    return before;
  };
  auto size_of = [&](uint32_t c) { return coarse_start[c + 1] - coarse_start[c]; };
  auto write_back = [&](const Held& h) {
    std::copy(h.sorted->begin(), h.sorted->begin() + size_of(h.bucket), occ.begin() + coarse_start[h.bucket]);
    later[h.bucket] = 1;
  };
  // Emits the held buckets whose prefix is known; with `all`, writes the others back. The release of a large
  // bucket's pages runs on all cores, isolated: this thread must not take up another worker's loop meanwhile
  // (it would share this one's buffers).
  auto settle = [&](Scratch& local, bool all) {
    std::erase_if(local.held, [&](const Held& h) {
      const uint32_t size = size_of(h.bucket);
      if (const std::optional<uint64_t> before = prefix(h.bucket)) {
        state[h.bucket].store(kPrefixed | (*before + count[h.bucket]), std::memory_order_release);
        emit(std::span<const Occ>(h.sorted->data(), size), uint32_t(*before));
        tbb::this_task_arena::isolate(
            [&] { release_pages(&occ[coarse_start[h.bucket]], size_t(size) * sizeof(Occ)); });
        return true;
      }
      if (all) write_back(h);
      return all;
    });
  };
  const int workers = tbb::this_task_arena::max_concurrency();
  tbb::parallel_for(0, workers, 1, [&](int) {
    Scratch& local = scratch.local();
    for (uint32_t c; (c = next.fetch_add(1)) < bk.coarse;) {
      const uint32_t begin = coarse_start[c], end = coarse_start[c + 1], size = end - begin;
      if (size == 0) {
        state[c].store(kCounted, std::memory_order_release);
        continue;
      }
      if (local.held.size() == kHeld) {  // every buffer holds a bucket: the oldest is written back
        write_back(local.held.front());
        local.held.erase(local.held.begin());
      }
      std::vector<Occ>* free = nullptr;
      for (std::vector<Occ>& b : local.buffers)
        if (std::none_of(local.held.begin(), local.held.end(), [&](const Held& h) { return h.sorted == &b; })) free = &b;
      std::vector<Occ>& sorted = *free;
      sorted.resize(std::max<size_t>(sorted.size(), size));
      std::vector<uint32_t>& fine_start = local.fine_start;
      counting_sort(&occ[begin], size, sorted.data(), size_t(1) << bk.shift, [](const Occ& o) { return o.fine; },
                    fine_start);
      for (size_t f = 0; f + 1 < fine_start.size(); ++f)
        if (fine_start[f + 1] - fine_start[f] > 1)
          sort_range(&sorted[fine_start[f]], &sorted[fine_start[f + 1]], n, local.tmp, local.starts);
      uint64_t heads = 1;
      for (uint32_t i = 1; i < size; ++i) heads += !same_xy(sorted[i], sorted[i - 1]);
      count[c] = uint32_t(heads);
      state[c].store(kCounted | heads, std::memory_order_release);
      local.held.push_back({c, &sorted});
      settle(local, false);
    }
    settle(local, true);
  });
  std::vector<uint32_t> first(size_t(bk.coarse) + 1, 0);  // every bucket's first vertex, then the count
  for (uint32_t c = 0; c < bk.coarse; ++c) first[c + 1] = first[c] + count[c];
  if (n >= (size_t(1) << 20))
    spdlog::debug("merge: {} of {} buckets emitted after the sort, {} points a bucket", std::count(later.begin(), later.end(), 1),
                  bk.coarse, n / bk.coarse);
  tbb::parallel_for(uint32_t(0), bk.coarse, [&](uint32_t c) {
    if (later[c]) emit(std::span<const Occ>(&occ[coarse_start[c]], coarse_start[c + 1] - coarse_start[c]), first[c]);
  });
  return first.back();
}

}  // namespace

PointMerge merge_points(std::span<const double> xy) {
  const size_t n = xy.size() / 2;
  PointMerge m;
  if (n == 0) return m;
  auto each = [&](size_t begin, size_t end, const auto& f) {
    for (size_t i = begin; i < end; ++i) f(i, xy[2 * i], xy[2 * i + 1], 0.0);
  };
  resize_unwritten(m.vertex_of, n);  // every element written below, on all cores
  resize_unwritten(m.first, n);      // at most n vertices; cut to their count below
  const uint32_t vertices = sort_occurrences<Occurrence>(
      each, n, [](double x, double y, double, uint32_t i) { return Occurrence{x, y, i, 0}; },
      [&](std::span<const Occurrence> s, uint32_t v) {
        for (size_t i = 0; i < s.size(); ++i) {
          if (i == 0 || !same_xy(s[i], s[i - 1])) m.first[v++] = s[i].occ;
          m.vertex_of[s[i].occ] = v - 1;
        }
      });
  m.first.resize(vertices);
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
  // The vertices in order: each group's head is its first occurrence (xy_less), whose coordinates and z it
  // keeps; a later z that differs is a conflict of that vertex. A group lies in one bucket.
  resize_unwritten(out.line_vertex_of, n - loose);
  resize_unwritten(out.vertices, n);  // at most n; cut to their count below (the pages past it never touched)
  struct Conflicts {
    double largest = 0;
    uint64_t vertices = 0;
  };
  tbb::enumerable_thread_specific<Conflicts> conflicts;
  const auto make = [](double x, double y, double z, uint32_t i) { return OccurrenceZ{x, y, z, i, 0}; };
  const auto emit = [&](std::span<const OccurrenceZ> s, uint32_t v) {
    Conflicts& c = conflicts.local();
    double hz = 0;
    bool conflicted = false;
    for (size_t i = 0; i < s.size(); ++i) {
      const OccurrenceZ& o = s[i];
      if (i == 0 || !same_xy(o, s[i - 1])) {
        out.vertices[v++] = {o.x, o.y, o.z};
        hz = o.z;
        conflicted = false;
      } else if (const double dz = std::abs(o.z - hz); dz != 0) {
        c.largest = std::max(c.largest, dz);
        c.vertices += !conflicted;
        conflicted = true;
      }
      if (o.occ >= loose) out.line_vertex_of[o.occ - loose] = v - 1;
    }
  };
  auto t = Clock::now();
  double scatter_ms = 0, freed_ms = 0;
  const uint32_t vertices = sort_occurrences<OccurrenceZ>(each, n, make, emit, [&] {
    // NaN would break the sort's strict weak order; readers reject it, this guards direct callers.
    if (bad)
      for (uint64_t i = 0; i < n; ++i)
        each(i, i + 1, [&](size_t, double x, double y, double z) {
          if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
            throw std::invalid_argument("prepare: vertex " + std::to_string(i) + " is not finite");
        });
    scatter_ms = ms_since(t);
    t = Clock::now();
    if (scattered) scattered();
    freed_ms = ms_since(t);
    t = Clock::now();
  });
  out.vertices.resize(vertices);
  for (const Conflicts& c : conflicts) {
    out.max_z_conflict = std::max(out.max_z_conflict, c.largest);
    out.z_conflicts += c.vertices;
  }
  spdlog::debug("prepare: merge: scatter {:.1f} ms, the input's points freed {:.1f} ms, sort and vertices {:.1f} ms",
                scatter_ms, freed_ms, ms_since(t));
  return out;
}

}  // namespace cdtgpu
