// half_edges (core/half_edges.hpp).
#include "core/half_edges.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <vector>

#include "core/parallel.hpp"

namespace cdtgpu {
namespace {

uint64_t key(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

// start[] of a canonical list, and corner[v] = v's last triangle's first half-edge where v starts one
// (kNoHalfEdge elsewhere, until half_edges finds one). A list out of canonical order is a logic_error: the
// twins rely on it.
void starts(const Triangles& ts, uint32_t V, HalfEdges& e) {
  const size_t T = ts.size();
  e.start = BigArray<uint32_t>(size_t(V) + 1);
  e.corner = BigArray<uint32_t>(V);
  std::atomic<bool> canonical{true};
  each(T + 1, [&](size_t t) {
    const uint32_t lo = t == 0 ? 0 : ts[t - 1][0] + 1, hi = t == T ? V : ts[t][0];
    if (t < T && (ts[t][1] <= ts[t][0] || ts[t][2] <= ts[t][0] || (t > 0 && ts[t] <= ts[t - 1])))
      canonical.store(false, std::memory_order_relaxed);
    for (uint32_t v = lo; v <= hi; ++v) e.start[v] = uint32_t(t);
    for (uint32_t v = lo; v < std::min(hi, V); ++v) e.corner[v] = kNoHalfEdge;
    if (t > 0 && lo <= hi) e.corner[lo - 1] = uint32_t(3 * (t - 1));
  });
  if (!canonical) throw std::logic_error("half_edges: the triangles are not in canonical order");
}

// The triangle in [start[v], start[v + 1]) whose corner k is w (half-edges between v and w), or kNoHalfEdge.
uint32_t find_in_range(const Triangles& ts, const HalfEdges& e, uint32_t v, int k, uint32_t w) {
  for (uint32_t s = e.start[v]; s < e.start[v + 1]; ++s)
    if (ts[s][k] == w) return s;
  return kNoHalfEdge;
}

}  // namespace

// Twins from the canonical order. In triangle (a, b, c), a the smallest, the twin of a -> b (b -> a) can only
// be the last half-edge of a triangle (a, x, b) or the middle one of a triangle starting below a; that of
// c -> a is the first of (a, c, x) or again a middle one. So each pair is found once: a -> b looks for its
// twin among a's triangles, a middle half-edge b -> c among min(b, c)'s, and the middle-to-middle pairs left
// (an edge whose two triangles both start elsewhere) meet in a sort by edge.
HalfEdges half_edges(const Triangles& ts, uint32_t V) {
  const size_t T = ts.size();
  HalfEdges e;
  starts(ts, V, e);
  e.twin = BigArray<uint32_t>(3 * T, kNoHalfEdge);
  auto pair = [&](uint32_t h, uint32_t g) { e.twin[h] = g, e.twin[g] = h; };
  // The middle half-edges left, by edge: each block appends its own at once (one slot per triangle at most,
  // pages touched only where written).
  BigArray<HalfEdgeKey> left(T);
  std::atomic<size_t> n_left{0};
  tbb::enumerable_thread_specific<std::vector<HalfEdgeKey>> block_left;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, T, kParallelGrain),
                    [&](const tbb::blocked_range<size_t>& r) {
                      auto& mine = block_left.local();
                      mine.clear();
                      // Backwards: min(b, c)'s triangles come after t, so they were just visited and are
                      // still in cache.
                      for (size_t t = r.end(); t-- > r.begin();) {
                        const uint32_t a = ts[t][0], b = ts[t][1], c = ts[t][2], h = uint32_t(3 * t);
                        if (const uint32_t s = find_in_range(ts, e, a, 2, b); s != kNoHalfEdge)
                          pair(h, 3 * s + 2);
                        const uint32_t lo = std::min(b, c), hi = std::max(b, c);
                        // A vertex that starts no triangle gets its corner here (any one will do).
                        if (e.start[lo] == e.start[lo + 1])
                          shared(e.corner[lo]).store(b < c ? h + 1 : h + 2, std::memory_order_relaxed);
                        if (e.start[hi] == e.start[hi + 1])
                          shared(e.corner[hi]).store(b < c ? h + 2 : h + 1, std::memory_order_relaxed);
                        if (const uint32_t s = find_in_range(ts, e, lo, b < c ? 2 : 1, hi); s != kNoHalfEdge)
                          pair(h + 1, 3 * s + (b < c ? 2 : 0));
                        else
                          mine.push_back({key(lo, hi), h + 1});
                      }
                      std::copy(mine.begin(), mine.end(), left.begin() + n_left.fetch_add(mine.size()));
                    });
  const size_t n = n_left;
  tbb::parallel_sort(left.begin(), left.begin() + n);
  each(n, [&](size_t i) {
    if (i + 1 < n && left[i].edge == left[i + 1].edge) pair(left[i].h, left[i + 1].h);
  });
  return e;
}

}  // namespace cdtgpu
