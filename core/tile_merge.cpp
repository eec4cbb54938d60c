// RunMerge and outside_final (core/tile_merge.hpp), on all cores.
#include "core/tile_merge.hpp"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "core/big_array.hpp"
#include "core/compact.hpp"
#include "core/half_edges.hpp"
#include "core/parallel.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

namespace {

// Runs freed on a thread of their own, so that the caller goes on: 24 GB at 1B points. One at a time (a second
// waits for the first, bounding the memory not yet given back); the last joined when the process exits.
class BackgroundFree {
 public:
  ~BackgroundFree() { join(); }
  void add(std::vector<Triangles> runs) {
    const std::lock_guard<std::mutex> lock(mutex_);
    join();
    thread_ = std::thread([runs = std::move(runs)]() mutable {
      for (Triangles& run : runs) free_storage(run);
    });
  }

 private:
  void join() {
    if (thread_.joinable()) thread_.join();
  }
  std::mutex mutex_;
  std::thread thread_;
};

void free_in_background(std::vector<Triangles> runs) {
  static BackgroundFree freeing;
  freeing.add(std::move(runs));
}

}  // namespace

void RunMerge::make_room(size_t triangles, unsigned threads) {
  room_made_ = std::async(std::launch::async, [this, triangles, threads] {
    resize_unwritten(room_, triangles);
    char* const p = reinterpret_cast<char*>(room_.data());
    const size_t bytes = room_.size() * sizeof(Triangle), piece = size_t(2) << 20;
    tbb::task_arena(int(std::max(1u, threads))).execute([&] {
      tbb::parallel_for(size_t(0), (bytes + piece - 1) / piece, [&](size_t i) {
        if (stop_.load(std::memory_order_relaxed)) return;
        for (size_t at = i * piece; at < std::min(bytes, (i + 1) * piece); at += 4096) p[at] = 0;
      });
    });
  });
}

namespace {

// Chunks of the runs' order between splitters: every step-th triangle of every run (about 16384 in all, at least
// 4096 triangles apart), sorted; chunk c holds what lies from splitter c - 1 up to splitter c, and begins in run r
// at at[c * runs + r] and in the order at start[c].
// Small chunks: a chunk where three runs meet (a slab's and its neighbour's, with the merge's between them)
// is one core's, and at 4096 chunks (500K triangles each, then sorted) those took the order from ~0.7
// to 1.25 s at 1B points on 4 devices. Not smaller: 2M points in 8 square tiles on 2 cores, chunks of 256
// triangles took 32 ms, of 4096 26 ms (the buckets before: 16).
struct Chunks {
  size_t count = 0, runs = 0;
  std::vector<size_t> at, start;
  // Run r's part of chunk c.
  std::span<const Triangle> piece(const std::vector<Triangles>& runs_of, size_t c, size_t r) const {
    return {runs_of[r].data() + at[c * runs + r], at[(c + 1) * runs + r] - at[c * runs + r]};
  }
};

Chunks chunks_of(const std::vector<Triangles>& runs) {
  Chunks k;
  const size_t r_count = k.runs = runs.size();
  size_t total = 0;
  for (const Triangles& run : runs) total += run.size();
  const size_t step = std::max<size_t>(4096, total / 16384);
  std::vector<Triangle> cut;
  for (const Triangles& run : runs)
    for (size_t i = step; i < run.size(); i += step) cut.push_back(run[i]);
  std::sort(cut.begin(), cut.end());
  cut.erase(std::unique(cut.begin(), cut.end()), cut.end());
  const size_t chunks = k.count = cut.size() + 1;
  k.at.assign((chunks + 1) * r_count, 0);
  k.start.assign(chunks + 1, 0);
  for (size_t r = 0; r < r_count; ++r) k.at[chunks * r_count + r] = runs[r].size();
  tbb::parallel_for(size_t(1), chunks, [&](size_t c) {
    for (size_t r = 0; r < r_count; ++r) {
      const Triangles& run = runs[r];
      const Triangle& x = cut[c - 1];  // most runs lie wholly on one side of it
      k.at[c * r_count + r] = run.empty() || !(run.front() < x) ? 0
                              : run.back() < x                 ? run.size()
                                  : size_t(std::lower_bound(run.begin(), run.end(), x) - run.begin());
    }
  });
  for (size_t c = 0; c <= chunks; ++c)
    for (size_t r = 0; r < r_count; ++r) k.start[c] += k.at[c * r_count + r];
  return k;
}

}  // namespace

OrderedRuns RunMerge::in_place(std::vector<Triangles>&& runs) {
  const auto t0 = std::chrono::steady_clock::now();
  const Chunks k = chunks_of(runs);
  // Each chunk's spans: the run whose head is least gives every triangle below the other heads' least at once
  // (a gallop to it), so a chunk of one run is one span, and the merge's few triangles among a slab's split it
  // only where they fall.
  std::vector<std::vector<std::span<const Triangle>>> of(k.count);
  tbb::parallel_for(size_t(0), k.count, [&](size_t c) {
    std::vector<std::span<const Triangle>> heads;
    for (size_t r = 0; r < k.runs; ++r)
      if (const auto p = k.piece(runs, c, r); !p.empty()) heads.push_back(p);
    auto& spans = of[c];
    while (heads.size() > 1) {
      size_t best = 0;
      for (size_t h = 1; h < heads.size(); ++h)
        if (heads[h].front() < heads[best].front()) best = h;
      const Triangle* next = nullptr;  // the least head of the others
      for (size_t h = 0; h < heads.size(); ++h)
        if (h != best && (!next || heads[h].front() < *next)) next = &heads[h].front();
      const std::span<const Triangle> b = heads[best];
      size_t hi = 1;  // b[0] < *next: the runs hold every triangle once
      while (hi < b.size() && b[hi] < *next) hi *= 2;
      const size_t lo = hi / 2, end = std::min(hi, b.size());
      const size_t take = size_t(std::lower_bound(b.begin() + lo, b.begin() + end, *next) - b.begin());
      spans.push_back(b.first(take));
      heads[best] = b.subspan(take);
      if (heads[best].empty()) heads.erase(heads.begin() + best);
    }
    if (!heads.empty()) spans.push_back(heads[0]);
  });
  std::vector<size_t> at(k.count + 1, 0);
  for (size_t c = 0; c < k.count; ++c) at[c + 1] = at[c] + of[c].size();
  std::vector<std::span<const Triangle>> spans(at.back());
  std::vector<size_t> place(at.back() + 1);  // each span's first triangle's place in the order
  place.back() = k.start.back();
  tbb::parallel_for(size_t(0), k.count, [&](size_t c) {
    size_t p = k.start[c];
    for (size_t i = 0; i < of[c].size(); ++i) {
      spans[at[c] + i] = of[c][i];
      place[at[c] + i] = p;
      p += of[c][i].size();
    }
    free_storage(of[c]);
  });
  spdlog::debug("canonical order, in place: {} spans in {} chunks in {:.0f} ms", spans.size(), k.count,
                ms_since(t0));
  return OrderedRuns(std::move(runs), TriangleSpans(std::move(spans), std::move(place)));
}

Triangles RunMerge::merge(std::vector<Triangles>& runs, size_t wave_bytes) {
  const auto t0 = std::chrono::steady_clock::now();
  const Chunks k = chunks_of(runs);
  const size_t r_count = runs.size(), chunks = k.count;
  const std::vector<size_t>& at = k.at;
  const std::vector<size_t>& start = k.start;
  const size_t total = start.back();
  const double split_ms = ms_since(t0);
  Triangles out;
  if (room_made_.valid()) room_made_.get();  // rethrows its allocation's error
  const bool in_room = room_.size() >= total;
  if (in_room)
    out = std::move(room_);
  else
    free_storage(room_);
  resize_unwritten(out, total);  // within the room: only the size changes
  const double room_ms = ms_since(t0);
  auto chunk = [&](size_t c) {
    Triangle* const to = out.data() + start[c];
    size_t pieces = 0, only = 0;
    for (size_t r = 0; r < r_count; ++r)
      if (at[(c + 1) * r_count + r] > at[c * r_count + r]) ++pieces, only = r;
    auto piece = [&](size_t r) { return k.piece(runs, c, r); };
    if (pieces == 1) {
      const auto p = piece(only);
      std::memcpy(static_cast<void*>(to), p.data(), p.size_bytes());
    } else if (pieces == 2) {
      size_t first = 0;
      while (at[(c + 1) * r_count + first] == at[c * r_count + first]) ++first;
      const auto p = piece(first), q = piece(only);
      std::merge(p.begin(), p.end(), q.begin(), q.end(), to);
    } else if (pieces > 2) {  // the smallest of the pieces' heads, again and again (few pieces: a scan)
      std::vector<std::span<const Triangle>> heads;
      for (size_t r = 0; r < r_count; ++r)
        if (!piece(r).empty()) heads.push_back(piece(r));
      for (Triangle* next = to; !heads.empty(); ++next) {
        size_t best = 0;
        for (size_t h = 1; h < heads.size(); ++h)
          if (heads[h].front() < heads[best].front()) best = h;
        *next = heads[best].front();
        heads[best] = heads[best].subspan(1);
        if (heads[best].empty()) heads.erase(heads.begin() + best);
      }
    }
  };
  // In waves of chunks (at most 64), each run's part of a wave given back after it: the output's pages are
  // touched as the runs' go. In room made ahead, one wave: the runs and the output are both whole already, so
  // giving pages back lowers no peak; it took ~100 ms of the order's 390 at 1B points (the copy alone ~290).
  const size_t waves =
      in_room ? 1 : std::clamp<size_t>(total * sizeof(Triangle) / std::max<size_t>(1, wave_bytes), 1, 64);
  size_t done = 0;
  for (size_t w = 1; w <= waves; ++w) {
    const size_t end =
        size_t(std::upper_bound(start.begin(), start.end() - 1, total * w / waves) - start.begin()) - 1;
    const size_t last = w == waves ? chunks : std::max(end, done);
    tbb::parallel_for(done, last, size_t(1), chunk);
    // One call a run and wave: a call a 768 KB block (each flushing every core's TLB) took the order from
    // ~1.0 to ~3.0 s in a cold run at 1B points on the 2 x H200 host.
    if (!in_room)
      for (size_t r = 0; r < r_count; ++r)
        release_pages(runs[r].data() + at[done * r_count + r],
                      (at[last * r_count + r] - at[done * r_count + r]) * sizeof(Triangle));
    done = last;
  }
  const double waves_ms = ms_since(t0);
  if (in_room) {
    std::vector<Triangles> gone(r_count);
    for (size_t r = 0; r < r_count; ++r) gone[r].swap(runs[r]);
    free_in_background(std::move(gone));
  } else {
    for (Triangles& run : runs) free_storage(run);
  }
  spdlog::debug(
      "canonical order: {} chunks split in {:.0f} ms, room at {:.0f}, merged at {:.0f}, runs freed at {:.0f}",
      chunks, split_ms, room_ms, waves_ms, ms_since(t0));
  return out;
}

Triangles outside_final(const Triangles& m, uint32_t V, const std::vector<Edge>& border) {
  // The merge's adjacency from its canonical order (core/half_edges) and its border edges listed under their
  // smaller end, each with its final side: a sort of every half-edge instead took 0.1-0.2 s at 1B points on 64
  // cores, serial work after the tiles.
  StepTimes steps;  // -v: where the time goes
  const HalfEdges e = half_edges(m, V);
  steps.add("adjacency");
  // sides[from[v] .. from[v + 1]): the border edges whose smaller end is v, as (larger end) << 1 | forward, where
  // forward says the final side is left of (smaller, larger).
  // Grouped on all cores (on one it was serial work after the tiles, as long as the border), a vertex's entries
  // in any order, which the lookup does not mind (an edge is listed once).
  RawVector<uint32_t> from, listed;
  group(border.size(), V, [&](size_t i) { return std::min(border[i][0], border[i][1]); }, from, listed,
        /*ascending=*/false);
  BigArray<uint64_t> sides(border.size());
  each(border.size(), [&](size_t k) {
    const Edge& b = border[listed[k]];
    sides[k] = uint64_t(std::max(b[0], b[1])) << 1 | (b[0] < b[1]);
  });
  steps.add("border table");
  // 0: a -> b is no border edge; else 1 + its forward bit.
  auto border_side = [&](uint32_t a, uint32_t b) -> int {
    const uint32_t lo = std::min(a, b), hi = std::max(a, b);
    for (uint32_t i = from[lo]; i < from[lo + 1]; ++i)
      if (sides[i] >> 1 == hi) return 1 + int(sides[i] & 1);
    return 0;
  };
  // The parts: triangles joined across edges that are not border edges (union-find linking the larger root
  // under the smaller, so concurrent unions make no cycle; the parts do not depend on the order).
  BigArray<uint32_t> parent(m.size());
  each(m.size(), [&](size_t t) { parent[t] = uint32_t(t); });
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
  // Each edge looked up once, its side kept for both its half-edges (side[h], border_side's answer): the lookups
  // are random reads, and the second pass made them again for every half-edge.
  const size_t halves = 3 * m.size();
  BigArray<uint8_t> side(halves);
  each(halves, [&](size_t h) {
    const uint32_t g = e.twin[h];
    if (g != kNoHalfEdge && g < h) return;  // its twin's
    const uint8_t s = uint8_t(border_side(from_of(m, uint32_t(h)), to_of(m, uint32_t(h))));
    side[h] = s;
    if (g == kNoHalfEdge) return;
    side[g] = s;
    if (!s) unite(uint32_t(h / 3), g / 3);
  });
  steps.add("parts");
  // Each part beside a border edge takes that edge's side: 1 final, 2 outside; a part with both is an error.
  BigArray<uint8_t> mark(m.size(), 0);
  each(halves, [&](size_t h) {
    if (const int s = side[h]) {
      const bool forward = from_of(m, uint32_t(h)) < to_of(m, uint32_t(h));
      // Read first: nearly every border half-edge meets one of a few large parts, whose mark all cores would
      // otherwise write at once.
      const uint8_t bit = forward == (s == 2) ? 1 : 2;
      const std::atomic_ref<uint8_t> mk = shared(mark[root(uint32_t(h / 3))]);
      if (!(mk.load(std::memory_order_relaxed) & bit)) mk.fetch_or(bit, std::memory_order_relaxed);
    }
  });
  steps.add("sides");
  Triangles kept = compact_as<Triangles>(
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
  steps.add("kept");
  spdlog::debug("the merge's triangles outside the final region ({} of {}; {} border edges), ms: {}", kept.size(),
                m.size(), border.size(), steps.text());
  return kept;
}

}  // namespace cdtgpu
