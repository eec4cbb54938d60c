// TriangleBuckets and outside_final (core/tile_merge.hpp), on all cores.
#include "core/tile_merge.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <chrono>

#include <spdlog/spdlog.h>

#include <sys/mman.h>

#include "core/compact.hpp"
#include "core/parallel.hpp"
#include "core/touched.hpp"

namespace cdtgpu {
namespace {

uint64_t key_of(uint32_t a, uint32_t b) { return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a; }

// Calls body(i, j) on all cores for blocks [i, j) of [0, n), each starting and ending at a group's boundary
// (same(i): item i is in item i - 1's group), so writes indexed by a group do not race.
template <class Same, class Body>
void group_blocks(size_t n, size_t grain, Same&& same, Body&& body) {
  auto inside_group = [&](size_t i) { return i > 0 && i < n && same(i); };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
    size_t i = r.begin(), j = r.end();
    while (inside_group(i)) ++i;
    while (inside_group(j)) ++j;
    if (i < j) body(i, j);
  });
}

// Calls f(i, j) for each group [i, j) of [0, n), on all cores; one call per group.
template <class Same, class F>
void each_group(size_t n, size_t grain, Same&& same, F&& f) {
  group_blocks(n, grain, same, [&](size_t i, size_t end) {
    while (i < end) {
      size_t j = i + 1;
      while (j < end && same(j)) ++j;
      f(i, j);
      i = j;
    }
  });
}

// A run sorted by first vertex, grouped by it.
auto same_first(std::span<const Triangle> run) {
  return [run](size_t i) { return run[i][0] == run[i - 1][0]; };
}

}  // namespace

TriangleBuckets::TriangleBuckets(size_t n) {
  resize_touched(count_, n);
  resize_touched(mixed_, n);
}

void TriangleBuckets::count(const Triangles& run) {
  each_group(run.size(), 1 << 16, same_first(run), [&](size_t i, size_t j) {
    const uint32_t v = run[i][0];
    if (count_[v]) mixed_[v] = 1;
    count_[v] += uint32_t(j - i);
  });
}

void TriangleBuckets::make_room(size_t triangles, unsigned threads) {
  room_made_ = std::async(std::launch::async, [this, triangles, threads] {
    resize_unwritten(room_, triangles);
    char* const p = reinterpret_cast<char*>(room_.data());
    const size_t bytes = room_.size() * sizeof(Triangle), piece = size_t(2) << 20;
    tbb::task_arena(int(std::max(1u, threads))).execute([&] {
      tbb::parallel_for(size_t(0), (bytes + piece - 1) / piece, [&](size_t i) {
        for (size_t at = i * piece; at < std::min(bytes, (i + 1) * piece); at += 4096) p[at] = 0;
      });
    });
  });
}

Triangles TriangleBuckets::place(std::vector<Triangles>& runs) {
  const auto t0 = std::chrono::steady_clock::now();
  auto ms_from = [](auto t) { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count(); };
  const size_t n = count_.size(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<uint64_t> base(blocks + 1, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {  // count_[v]: where bucket v starts in its block
    uint32_t at = 0;
    for (size_t v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) at += std::exchange(count_[v], at);
    base[b + 1] = at;
  });
  for (size_t b = 0; b < blocks; ++b) base[b + 1] += base[b];
  size_t total = 0;
  for (const Triangles& run : runs) total += run.size();
  if (total != base[blocks])
    throw std::logic_error("tiles: " + std::to_string(total) + " triangles to order, " +
                           std::to_string(base[blocks]) + " counted");
  // In waves of vertex ids (about 512 MB of triangles each, at most 64), each run's part of a wave (a run is
  // sorted by first vertex) copied, then its pages given back: the output's pages are touched as the runs' go,
  // so the order holds the triangles about once, not twice. Run by run, the first run touched most of the
  // output: a tile's vertices spread over its column's whole id range. Within a wave the tiles' runs (all but
  // the last) at once, as they share no first vertex; the merge's last, as a border vertex has triangles in
  // it and in a tile's. 64 waves of 65 runs for 2.5M vertices took 41-54 ms on 16 threads.
  const double prefix_ms = ms_from(t0);
  Triangles out;
  if (room_made_.valid()) room_made_.get();  // rethrows its allocation's error
  if (room_.size() >= total)
    out = std::move(room_);
  else
    free_storage(room_);
  resize_unwritten(out, total);  // within the room: only the size changes
  const double room_ms = ms_from(t0);
  const size_t waves = std::clamp<size_t>(total * sizeof(Triangle) >> 29, 1, 64);
  std::vector<size_t> done(runs.size(), 0);
  for (size_t w = 1; w <= waves; ++w) {
    const uint64_t end = uint64_t(n) * w / waves;
    auto place_part = [&](size_t r) {
      const Triangles& run = runs[r];
      const size_t to = size_t(std::partition_point(run.begin() + done[r], run.end(),
                                                    [&](const Triangle& t) { return t[0] < end; }) -
                               run.begin());
      if (to == done[r]) return;  // a run's vertices lie in its tile's column: most waves miss it
      const std::span<const Triangle> part(run.data() + done[r], to - done[r]);
      // Triangle by triangle, not a copy call a group: most groups hold one or two triangles.
      group_blocks(part.size(), 1 << 16, same_first(part), [&](size_t i, size_t j) {
        for (; i < j; ++i) {
          const uint32_t v = part[i][0];
          out[base[v / kBlock] + count_[v]++] = part[i];
        }
      });
      // One call a part: a call a 768 KB block (each flushing every core's TLB) took canonical order from ~1.0
      // to ~3.0 s in a cold run at 1B points on the 2 x H200 host, and no less in warm ones.
      release_pages(part.data(), part.size_bytes());
      done[r] = to;
    };
    tbb::parallel_for(size_t(0), runs.size() - 1, size_t(1), place_part);
    place_part(runs.size() - 1);
  }
  const double waves_ms = ms_from(t0);
  for (Triangles& run : runs) free_storage(run);
  const double free_ms = ms_from(t0);
  each(n, [&](size_t v) {  // count_[v] is now bucket v's end in its block, count_[v - 1] its start
    if (!mixed_[v]) return;
    const auto at = out.begin() + base[v / kBlock];
    std::sort(at + (v % kBlock ? count_[v - 1] : 0), at + count_[v]);
  });
  spdlog::debug("canonical order: prefix {:.0f} ms, room to {:.0f}, waves to {:.0f}, runs freed to {:.0f}, mixed sorted to {:.0f}", prefix_ms,
                room_ms, waves_ms, free_ms, ms_from(t0));
  return out;
}

Triangles outside_final(const Triangles& m, const std::vector<Edge>& border) {
  // Every edge of every triangle, and each border edge as one more entry after its triangles' (triangle
  // kBorder), sorted: a group of equal keys is one edge. On all cores: the level-1 keep of a 2.5M-vertex run
  // was 100-140 ms of a 16-thread host's ~800 ms with the border looked up and the parts joined on one core.
  constexpr uint32_t kBorder = UINT32_MAX;
  struct HalfEdge {
    uint64_t key;
    uint32_t triangle;
    bool forward;  // runs from min to max: the triangle (or the border's final side) is left of (min, max)
  };
  const size_t halves = 3 * m.size();
  std::vector<HalfEdge> half(halves + border.size());
  tbb::parallel_for(size_t(0), m.size(), [&](size_t t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m[t][k], b = m[t][(k + 1) % 3];
      half[3 * t + k] = {key_of(a, b), uint32_t(t), a < b};
    }
  });
  tbb::parallel_for(size_t(0), border.size(), [&](size_t i) {
    half[halves + i] = {key_of(border[i][0], border[i][1]), kBorder, border[i][0] < border[i][1]};
  });
  tbb::parallel_sort(half.begin(), half.end(), [](const HalfEdge& p, const HalfEdge& q) {
    return p.key != q.key ? p.key < q.key : p.triangle < q.triangle;
  });
  // The parts: triangles joined across edges that are not border edges (union-find linking the larger root
  // under the smaller, so concurrent unions make no cycle; the parts do not depend on the order).
  std::vector<uint32_t> parent(m.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto root = [&](uint32_t t) {
    for (;;) {
      uint32_t p = std::atomic_ref<uint32_t>(parent[t]).load(std::memory_order_relaxed);
      if (p == t) return t;
      const uint32_t g = std::atomic_ref<uint32_t>(parent[p]).load(std::memory_order_relaxed);
      if (g != p) std::atomic_ref<uint32_t>(parent[t]).compare_exchange_weak(p, g, std::memory_order_relaxed);
      t = g;
    }
  };
  auto unite = [&](uint32_t a, uint32_t b) {
    for (;;) {
      a = root(a), b = root(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      uint32_t expected = a;
      if (std::atomic_ref<uint32_t>(parent[a]).compare_exchange_strong(expected, b, std::memory_order_relaxed))
        return;
    }
  };
  // Each group of equal keys is one edge.
  auto each_edge = [&](auto&& f) {
    each_group(half.size(), 1 << 14, [&](size_t i) { return half[i].key == half[i - 1].key; }, f);
  };
  each_edge([&](size_t i, size_t j) {
    if (half[j - 1].triangle != kBorder && j == i + 2) unite(half[i].triangle, half[i + 1].triangle);
  });
  // Each part beside a border edge takes that edge's side: 1 final, 2 outside; a part with both is an error.
  std::vector<uint8_t> mark(m.size(), 0);
  each_edge([&](size_t i, size_t j) {
    const HalfEdge& b = half[j - 1];
    if (b.triangle != kBorder) return;
    for (size_t k = i; half[k].triangle != kBorder; ++k)
      std::atomic_ref<uint8_t>(mark[root(half[k].triangle)])
          .fetch_or(half[k].forward == b.forward ? 1 : 2, std::memory_order_relaxed);
  });
  half = {};
  return compact_as<Triangles>(
      m.size(),
      [&](size_t t) {
        const uint8_t mk = mark[root(uint32_t(t))];
        if (mk == 3)
          throw std::logic_error("tile merge: a part of the merge lies on both sides of the final region's border");
        return mk != 1;
      },
      [&](size_t t, Triangle* at) {
        if (mark[root(uint32_t(t))] != 1) *at++ = m[t];
        return at;
      });
}

}  // namespace cdtgpu
