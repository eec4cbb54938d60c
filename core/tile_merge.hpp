// The merge's bookkeeping for core/tiles: which of a merge's triangles to keep, and the canonical order of
// the sorted runs (each tile's final triangles, the merge's) that together make the whole mesh.
//
//   RunMerge order;
//   order.make_room(2 * vertices, threads);        // optional: the output's pages beside the tiles
//   Triangles kept = outside_final(merge, vertices, border); // the merge's, outside the tiles' final region
//   Triangles all = order.merge(runs);             // runs: the tiles' runs and the merge's
//   OrderedRuns left = order.in_place(std::move(runs));  // or: the order's spans, for a writer (no copy)
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <future>
#include <vector>

#include "core/model.hpp"
#include "core/triangle_spans.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {

// The canonical order of sorted runs that together hold every triangle once: their merge, in chunks between
// splitters sampled from the runs, on all cores. A chunk that only one run reaches (nearly all, for slabs:
// only the merge's triangles interleave with a tile's, near the cuts) is one copy; two are merged; more
// (where a slab's run, the merge's and the next slab's meet, or square tiles' runs, which interleave across
// their column's ids) give the smallest of their heads again and again. The runs' pages are given back as the
// chunks pass them, so without room made ahead the order holds the triangles about once. It replaced buckets
// by first vertex (counted as the tiles came, then placed triangle by triangle), which read and wrote a
// 4-byte count a vertex and took 580-650 ms at 1B points + 250M segments on the 2 x H200 host.
class RunMerge {
 public:
  // The output's pages, for up to `triangles` (an upper bound of the total), touched in the background on
  // `threads` cores, so that merge() copies into touched memory: at 1B points + 250M segments on the 2 x H200
  // host (32 cores) the order's copy into fresh memory took 780-890 ms, and a copy of 24 GB into touched
  // memory takes 350. It holds the whole output beside the runs: for hosts with the memory to spare.
  void make_room(size_t triangles, unsigned threads);

  // The runs (each sorted, canonical), freed, as one sorted list; in waves of about wave_bytes of triangles,
  // or, in room made ahead, in one wave, the runs freed on another thread after it.
  Triangles merge(std::vector<Triangles>& runs, size_t wave_bytes = size_t(512) << 20);

  // The same order left in the runs: their spans in order (a chunk of one run is one span), no copy. A mesh
  // writer reads them as they are; at 1B points + 250M segments the copy is 24 GB (merge(): 0.3-0.4 s on 32
  // cores, 1.1-1.25 s on 16, with the room's 24 GB more of memory, or its pages given back wave by wave).
  OrderedRuns in_place(std::vector<Triangles>&& runs);

  // A run given up (a tile that throws, such as UnresolvedTile) stops the touching at once: its caller would
  // otherwise wait for it (24 GB on a quarter of the cores at 1B points) before resolving and tiling again.
  ~RunMerge() { stop_.store(true); }

 private:
  Triangles room_;
  std::atomic<bool> stop_{false};
  std::future<void> room_made_;  // last: joined (in its destructor, after ours) before room_ goes
};

// The merge's triangles outside the final region: the merge triangulates the final region's holes too, from
// their border vertices; those triangles lie in parts of the merge, bounded by border edges, that are on the
// final side of a border edge (tiling.md, claim 2). `border` is directed with the final region on its left; `m`
// is in canonical order (a logic_error otherwise), as a triangulation's output is, over `vertices` vertices.
Triangles outside_final(const Triangles& m, uint32_t vertices, const std::vector<Edge>& border);

}  // namespace cdtgpu
