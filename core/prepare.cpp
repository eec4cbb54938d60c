// prepare: merges exact duplicate (x, y) vertices and turns polylines into unique index segments.
// Cost: two sorts (all occurrences by (x, y) in core/merge_points.cpp, all segments by index pair), no hashing,
// so the result is the same on every run. Both sorts run on all cores: both orders are total, so any correct
// sort gives the same result. The merge of duplicates is a parameter: the
// GPU backend passes gpu::merge_points, which gives the same answer (tests/gpu_dedupe_test.cpp).
#include "core/prepare.hpp"

#include "core/compact.hpp"
#include "core/counting_sort.hpp"
#include "core/parallel.hpp"
#include "core/touched.hpp"
#include "core/uninit.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <atomic>
#include <exception>
#include <cmath>
#include <execution>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

namespace cdtgpu {

namespace {

struct SegmentKey {
  uint64_t ab;    // a << 32 | b with a < b: sorting the key sorts by (a, b)
  uint32_t line;  // polyline index, so that a shared segment keeps its first line
};

bool key_less(const SegmentKey& s, const SegmentKey& t) { return s.ab != t.ab ? s.ab < t.ab : s.line < t.line; }

// The n segments sorted by (ab, line) on all cores: `each(begin, end, f)` calls f(segment) for the segments [begin,
// end) in order, made on the fly from the lines. A bucket pass by a (a vertex id below `vertices`) writes each
// segment once to its bucket's place, then each bucket is sorted in cache. std::sort(par) of 250M segments (4 GB)
// took 1.5-1.8 s on 16 threads at 1B points; written in line order first and then bucketed, each segment was
// written twice and read three times (0.99-1.15 s for both at 1B points on one H200, the segments' pass alone
// 0.13-0.15 s).
// `zero_length`: how many have a == b.
template <class Each>
RawVector<SegmentKey> sorted_segments(size_t n, uint64_t vertices, const Each& each, uint64_t& zero_length) {
  auto zero = [](const SegmentKey& k) { return (k.ab >> 32) == (k.ab & 0xffffffffu); };
  RawVector<SegmentKey> out;
  resize_unwritten(out, n);
  zero_length = 0;
  if (n < (size_t(1) << 20)) {
    size_t at = 0;
    each(0, n, [&](const SegmentKey& k) {
      zero_length += zero(k);
      out[at++] = k;
    });
    std::sort(std::execution::par, out.begin(), out.end(), key_less);
    return out;
  }
  // About 4096 segments a bucket (64 KB), at most 2^16 buckets; blocks of the input count their buckets.
  const uint64_t last = std::max<uint64_t>(vertices, 1) - 1;  // the largest first vertex
  const uint64_t most = std::clamp<uint64_t>(n / 4096, 1, uint64_t(1) << 16);
  uint32_t shift = 0;
  while ((last >> shift) >= most) ++shift;
  const size_t buckets = size_t(last >> shift) + 1;
  const size_t blocks = 256, block = (n + blocks - 1) / blocks;
  std::vector<uint32_t> place(blocks * buckets, 0);
  auto bucket = [&](const SegmentKey& k) { return size_t(k.ab >> 32 >> shift); };
  std::atomic<uint64_t> zeros{0};
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* h = &place[b * buckets];
    uint64_t z = 0;
    each(std::min(n, b * block), std::min(n, (b + 1) * block), [&](const SegmentKey& k) {
      ++h[bucket(k)];
      z += zero(k);
    });
    zeros += z;
  });
  zero_length = zeros;
  std::vector<size_t> start(buckets + 1, 0);  // bucket starts; then each block's places, bucket by bucket
  for (size_t b = 0; b < blocks; ++b)
    for (size_t k = 0; k < buckets; ++k) start[k + 1] += place[b * buckets + k];
  for (size_t k = 0; k < buckets; ++k) start[k + 1] += start[k];
  tbb::parallel_for(size_t(0), buckets, [&](size_t k) {
    size_t at = start[k];
    for (size_t b = 0; b < blocks; ++b) at += std::exchange(place[b * buckets + k], uint32_t(at - start[k]));
  });
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* at = &place[b * buckets];
    each(std::min(n, b * block), std::min(n, (b + 1) * block), [&](const SegmentKey& s) {
      const size_t k = bucket(s);
      out[start[k] + at[k]++] = s;
    });
  });
  // Each bucket by a counting sort of its first vertices (2^shift of them, their counts in cache), then each
  // vertex's few by (b, line): std::sort of the buckets' ~4096 took ~0.5 s of the 0.9 at 1B points on 32 threads.
  struct Scratch {
    std::vector<uint32_t> count;
    std::vector<SegmentKey> sorted;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(size_t(0), buckets, [&](size_t k) {
    SegmentKey* const first = out.data() + start[k];
    const size_t m = start[k + 1] - start[k];
    // Few segments over many first vertices (a sparse bucket): the counts would outweigh them.
    if (m < 64 || (size_t(1) << shift) > 16 * m) return std::sort(first, first + m, key_less);
    Scratch& local = scratch.local();
    std::vector<uint32_t>& count = local.count;
    auto low = [&](const SegmentKey& s) { return size_t(s.ab >> 32) - (k << shift); };
    local.sorted.resize(std::max(local.sorted.size(), m));
    counting_sort(first, m, local.sorted.data(), size_t(1) << shift, low, count);
    std::copy(local.sorted.begin(), local.sorted.begin() + m, first);
    for (size_t j = 0; j + 1 < count.size(); ++j)
      if (count[j + 1] - count[j] > 1) std::sort(first + count[j], first + count[j + 1], key_less);
  });
  return out;
}

// prepare with a merger of coordinates (the GPU's): every occurrence's coordinates gathered in reading order on
// all cores (lines start at known offsets), merged, then the vertices and their z conflicts gathered by index.
template <class Phase>
RawVector<uint32_t> gather_and_merge(const InputSet& in, const std::vector<uint64_t>& line_at,
                                     const PointMerger& merge, const std::function<void()>& gathered,
                                     PreparedInput& out, const Phase& phase) {
  const uint64_t total = line_at.back();
  RawVector<double> xy, z;
  resize_unwritten(xy, 2 * total);
  resize_unwritten(z, total);
  std::atomic<bool> bad{false};
  auto put = [&](uint64_t i, const Point3& p) {
    // NaN would break the sort's strict weak order; readers reject it, this guards direct callers.
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) bad.store(true, std::memory_order_relaxed);
    xy[2 * i] = p.x;
    xy[2 * i + 1] = p.y;
    z[i] = p.z;
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, in.points.size(), 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) put(i, in.points[i]);
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, in.lines.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t l = r.begin(); l < r.end(); ++l)
      for (size_t k = 0; k < in.lines[l].points.size(); ++k) put(line_at[l] + k, in.lines[l].points[k]);
  });
  if (bad)
    for (size_t i = 0; i < total; ++i)
      if (!std::isfinite(xy[2 * i]) || !std::isfinite(xy[2 * i + 1]) || !std::isfinite(z[i]))
        throw std::invalid_argument("prepare: vertex " + std::to_string(i) + " is not finite");
  if (gathered) gathered();
  phase("gather");
  // The merged vertices: coordinates and z of their first occurrence; conflicts where a later z differs.
  PointMerge m = merge(xy);
  phase("merge");
  if (m.vertex_of.size() != total || m.first.size() > total)
    throw std::logic_error("prepare: the point merge returned " + std::to_string(m.vertex_of.size()) +
                           " of " + std::to_string(total) + " points");
  const RawVector<uint32_t>& vertex_of = m.vertex_of;
  // Both loops gather at random (cache misses): in parallel (TBB), each result independent of the split.
  resize_unwritten(out.vertices, m.first.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, m.first.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const uint32_t i = m.first[v];
      out.vertices[v] = {xy[2 * size_t(i)], xy[2 * size_t(i) + 1], z[i]};
    }
  });
  std::vector<uint8_t> conflict;
  resize_touched(conflict, out.vertices.size());  // zeroed on all cores
  out.max_z_conflict = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, total), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double largest) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const double dz = std::abs(z[i] - out.vertices[vertex_of[i]].z);
          if (dz != 0) {
            std::atomic_ref<uint8_t>(conflict[vertex_of[i]]).store(1, std::memory_order_relaxed);
            largest = std::max(largest, dz);
          }
        }
        return largest;
      },
      [](double a, double b) { return std::max(a, b); });
  out.z_conflicts = count_if(conflict.size(), [&](size_t v) { return conflict[v] != 0; });
  free_storage(xy);
  free_storage(z);
  phase("vertices");
  return std::move(m.vertex_of);
}

}  // namespace

PreparedInput prepare(const InputSet& in, const PointMerger& merge, const std::function<void()>& gathered,
                      const VerticesAhead& ahead) {
  using Clock = std::chrono::steady_clock;
  auto t = Clock::now();
  auto phase = [&](const char* name) {
    spdlog::debug("prepare: {} {:.1f} ms", name, std::chrono::duration<double, std::milli>(Clock::now() - t).count());
    t = Clock::now();
  };
  PreparedInput out;
  uint64_t total = in.points.size();
  for (const Polyline& l : in.lines) total += l.points.size();
  if (total >= std::numeric_limits<uint32_t>::max())
    throw std::length_error("prepare: " + std::to_string(total) +
                            " input vertices exceed the 32-bit index range");
  out.input_points = total;

  std::vector<uint64_t> line_at(in.lines.size() + 1, in.points.size());
  for (size_t i = 0; i < in.lines.size(); ++i) line_at[i + 1] = line_at[i] + in.lines[i].points.size();
  // Only the lines' sizes and closed flags are read once the points are gathered (line_at, seg_at).
  auto segments_of = [&](const Polyline& l) -> uint64_t {
    const uint64_t n = l.points.size();
    return n < 2 ? 0 : (l.closed && n >= 3 ? n : n - 1);
  };
  std::vector<uint64_t> seg_at(in.lines.size() + 1, 0);
  for (size_t li = 0; li < in.lines.size(); ++li) seg_at[li + 1] = seg_at[li] + segments_of(in.lines[li]);
  // The vertex of every line point: line point i is occurrence line_at[0] + i.
  RawVector<uint32_t> vertex_of;
  const uint32_t* line_vertex_of = nullptr;
  if (merge) {
    vertex_of = gather_and_merge(in, line_at, merge, gathered, out, phase);
    line_vertex_of = vertex_of.data() + line_at[0];
  } else {
    MergedInput m = merge_input(in, gathered);
    phase("merge");
    vertex_of = std::move(m.line_vertex_of);
    line_vertex_of = vertex_of.data();
    out.vertices = std::move(m.vertices);
    out.z_conflicts = m.z_conflicts;
    out.max_z_conflict = m.max_z_conflict;
  }
  if (vertex_of.size() != (merge ? total : total - line_at[0]) || out.vertices.size() > total)
    throw std::logic_error("prepare: the point merge returned " + std::to_string(vertex_of.size()) + " of " +
                           std::to_string(total) + " points");
  out.merged_duplicates = total - out.vertices.size();
  // Declared after `out`: on a throw from here on, abandoned() runs before out's vertices go.
  struct Abandon {
    const VerticesAhead& ahead;
    int exceptions = std::uncaught_exceptions();
    bool shown = false;
    ~Abandon() {
      if (shown && std::uncaught_exceptions() > exceptions && ahead.abandoned) ahead.abandoned();
    }
  } abandon{ahead};
  if (ahead.made) {
    ahead.made(out.vertices);
    abandon.shown = true;
  }

  // Segments of every polyline, the closing edge of every ring included (counted per line above), made where
  // the sort reads them: segment i of the whole is segment i - seg_at[li] of the line li holding it.
  out.input_segments = seg_at.back();
  auto each_segment = [&](size_t begin, size_t end, const auto& f) {
    if (begin >= end) return;
    size_t li = size_t(std::upper_bound(seg_at.begin(), seg_at.end(), begin) - seg_at.begin()) - 1;
    for (size_t i = begin; i < end; ++li) {
      const uint64_t base = line_at[li] - line_at[0], n = line_at[li + 1] - line_at[li];
      for (uint64_t k = i - seg_at[li]; i < std::min<uint64_t>(end, seg_at[li + 1]); ++i, ++k) {
        uint32_t a = line_vertex_of[base + k], b = line_vertex_of[base + (k + 1) % n];
        if (a > b) std::swap(a, b);
        f(SegmentKey{uint64_t(a) << 32 | b, uint32_t(li)});  // a == b: dropped after the sort
      }
    }
  };
  // The constraints' storage, for as many as there are segments (the kept ones are fewer), made on a thread of its
  // own beside the sort: a std::vector's resize zeroes it on one core whatever was done before (at 1B points
  // + 250M segments, 2 GB: ~0.2 s of the critical path after the sort).
  std::exception_ptr sizing_failed;
  std::thread sizing([&] {
    try {
      out.constraints.reserve(out.input_segments);
      advise_huge_pages(out.constraints.data(), out.input_segments * sizeof(Edge));
      out.constraints.resize(out.input_segments);
    } catch (...) {
      sizing_failed = std::current_exception();
    }
  });
  RawVector<SegmentKey> segs;
  try {
    segs = sorted_segments(out.input_segments, out.vertices.size(), each_segment, out.zero_length_segments);
  } catch (...) {
    sizing.join();
    throw;
  }
  sizing.join();
  if (sizing_failed) std::rethrow_exception(sizing_failed);
  phase("segments and their sort");
  // The first of each run of equal keys, zero-length ones left out; the kept ones in order, on all cores.
  auto kept = [&](size_t i) {
    const uint64_t ab = segs[i].ab;
    return (ab >> 32) != (ab & 0xffffffffu) && (i == 0 || segs[i - 1].ab != ab);
  };
  // Both lists from one count and one pass (two compactions read the 4 GB of keys at 1B points four times).
  const std::vector<size_t> first = compact_starts(segs.size(), kept);
  out.constraints.resize(first.back());  // no more than sized above: nothing written
  resize_unwritten(out.constraint_line, first.back());  // every element written below
  tbb::parallel_for(size_t(0), first.size() - 1, [&](size_t b) {
    size_t at = first[b];
    for (size_t i = b * kCompactBlock; i < std::min(segs.size(), (b + 1) * kCompactBlock); ++i)
      if (kept(i)) {
        out.constraints[at] = {uint32_t(segs[i].ab >> 32), uint32_t(segs[i].ab & 0xffffffffu)};
        out.constraint_line[at++] = segs[i].line;
      }
  });
  out.duplicate_segments = out.input_segments - out.zero_length_segments - out.constraints.size();
  phase("constraints");
  return out;
}

}  // namespace cdtgpu
