// The merge's bookkeeping for core/tiles: which of a merge's triangles to keep, and the canonical order of the
// sorted runs (each tile's final triangles, the merge's) that together make the whole mesh.
//
//   TriangleBuckets buckets(vertices);
//   buckets.make_room(2 * vertices, threads);      // optional: the output's pages beside the tiles
//   buckets.count(tile_run);                       // as each tile's final triangles come
//   Triangles kept = outside_final(merge, border); // the merge's, outside the tiles' final region
//   buckets.count(kept);
//   Triangles all = buckets.place(runs);           // runs: the tiles' runs, then the merge's last
#pragma once
#include <cstddef>
#include <cstdint>
#include <future>
#include <vector>

#include "core/model.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {

// The canonical order of sorted runs that together hold every triangle once (first vertices below n): each
// triangle goes to its first vertex's bucket, laid out by counts and prefix sums. Runs are counted as they
// come (a tile's while the others are on the device) and placed at the end. A run's triangles of one vertex
// arrive together and in order, so only the buckets filled from two runs (vertices on the final region's
// border: a tile's final triangles and the merge's) are sorted afterwards. A heap merge of the runs took 1.5 s
// for 512M triangles on 16 threads.
class TriangleBuckets {
 public:
  explicit TriangleBuckets(size_t n);  // first vertices below n

  // The output's pages, for up to `triangles` (an upper bound of the total), touched in the background on
  // `threads` cores, so that place() copies into touched memory: at 1B points + 250M segments on the 2 x H200
  // host (32 cores) the order's copy into fresh memory took 780-890 ms, and a copy of 24 GB into touched memory
  // takes 350. It holds the whole output beside the runs (not about once, as place() alone does): for hosts with
  // the memory to spare.
  void make_room(size_t triangles, unsigned threads);

  // Runs counted at the same time have no first vertex in common: a tile's final triangles are made of its own
  // vertices.
  void count(const Triangles& run);

  // The counted runs, freed one by one, as one sorted list. Offsets are 32-bit within blocks of vertices. Every
  // run but the last is a tile's (no first vertex in common), the last the merge's.
  Triangles place(std::vector<Triangles>& runs);

 private:
  static constexpr size_t kBlock = 1 << 16;
  RawVector<uint32_t> count_;
  RawVector<uint8_t> mixed_;
  Triangles room_;
  std::future<void> room_made_;  // last: joined before room_ goes
};

// The merge's triangles outside the final region: the merge triangulates the final region's holes too, from
// their border vertices; those triangles lie in parts of the merge, bounded by border edges, that are on the
// final side of a border edge (tiling.md, claim 2). `border` is directed with the final region on its left.
Triangles outside_final(const Triangles& m, const std::vector<Edge>& border);

}  // namespace cdtgpu
