// The checks run as parallel passes over triangles, corners and vertices (TBB, as core/regions.cpp does); only
// the boundary walk, the pocket filling and the convexity test run on one core, and the boundary is O(sqrt n).
// Every pass gives the same result on every run: groups are sorted after their atomic scatter, offenders are
// sorted by the caller, and the one ordered choice (the lowest vertex) is a reduction with index tie-breaks.
// Each corner's twin is looked up once (boundary) and reused by the fans and the slots. The pockets' triangles
// go after the dual's (sorted) ones; the index is patched for them and the boundary checked again on the old
// cycle's vertices only, the only ones they touch.
#include "gpu/voronoi_check.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "core/parallel.hpp"
#include "core/predicates.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

constexpr uint32_t kNone = UINT32_MAX;

using Array = RawVector<uint32_t>;

// Every element of `a` set to `value`, on all cores.
void set_all(Array& a, size_t size, uint32_t value) {
  a.resize(size);
  each(size, [&](size_t i) { a[i] = value; });
}

// Offenders found on all cores; their order does not matter (the caller sorts them).
struct Blame {
  tbb::enumerable_thread_specific<std::vector<uint32_t>> local;
  void add(uint32_t v) { local.local().push_back(v); }
  void into(std::vector<uint32_t>& off) {
    for (std::vector<uint32_t>& l : local) {
      off.insert(off.end(), l.begin(), l.end());
      l.clear();
    }
  }
};

struct Geometry {
  std::span<const double> xy;
  pred::XY at(uint32_t i) const { return {xy[2 * i], xy[2 * i + 1]}; }
  int orient(uint32_t a, uint32_t b, uint32_t c) const { return pred::orient2d(at(a), at(b), at(c)); }
  bool less(uint32_t a, uint32_t b) const {  // canonical (x, y) order
    const pred::XY p = at(a), q = at(b);
    return p.x < q.x || (p.x == q.x && p.y < q.y);
  }
  bool between(uint32_t a, uint32_t b, uint32_t c) const {  // b strictly inside segment a-c, given collinear
    return (less(a, b) && less(b, c)) || (less(c, b) && less(b, a));
  }
  // The direction u - v has its angle in [0, pi): exact, by comparisons only. A counter-clockwise turn of less
  // than pi crosses angle 0 exactly when it goes from a lower direction to an upper one, so counting those
  // counts how often a fan or a polygon winds.
  bool upper(uint32_t v, uint32_t u) const {
    const pred::XY p = at(v), q = at(u);
    return q.y > p.y || (q.y == p.y && q.x > p.x);
  }
};

// Each triangle rotated to start at its smallest vertex; sorted, duplicates removed. By buckets of the first
// vertex (a counting sort), then each bucket's few triangles by their other two: O(F) on all cores.
RawVector<Triangle> normalise(RawVector<Triangle> tris, size_t points) {
  each(tris.size(), [&](size_t i) {
    Triangle& t = tris[i];
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  });
  Array first, items;
  group(tris.size(), points, [&](size_t i) { return tris[i][0]; }, first, items);
  Array kept(points + 1);
  kept[0] = 0;
  each(points, [&](size_t v) {
    auto b = items.begin() + first[v], e = items.begin() + first[v + 1];
    std::sort(b, e, [&](uint32_t i, uint32_t j) { return tris[i] < tris[j]; });
    e = std::unique(b, e, [&](uint32_t i, uint32_t j) { return tris[i] == tris[j]; });
    kept[v + 1] = uint32_t(e - b);
  });
  prefix_sums(kept);
  RawVector<Triangle> out(kept[points]);
  each(points, [&](size_t v) {
    for (uint32_t k = 0; k < kept[v + 1] - kept[v]; ++k) out[kept[v] + k] = tris[items[first[v] + k]];
  });
  return out;
}

// Triangles and, per vertex, its corners (3t + j, ascending), each the start of the directed edge
// t[j] -> t[j + 1], with that edge's head beside it.
struct Mesh {
  RawVector<Triangle> tris;
  Array first, corners, heads;
  Array twin;  // per corner: edge(head, tail of the edge), set by boundary()

  void index(size_t points) {
    group(tris.size() * 3, points, [&](size_t c) { return tris[c / 3][c % 3]; }, first, corners);
    heads.resize(corners.size());
    each(corners.size(), [&](size_t i) { heads[i] = head(corners[i]); });
  }
  // The index again after appending tris[before ..] (a few triangles, at few vertices): their corners go after
  // each vertex's others, as index() would put them, in one copying pass.
  void reindex(size_t before, size_t points) {
    std::vector<std::pair<uint32_t, uint32_t>> added;  // (vertex, corner)
    for (size_t t = before; t < tris.size(); ++t)
      for (uint32_t j = 0; j < 3; ++j) added.push_back({tris[t][j], uint32_t(3 * t + j)});
    std::sort(added.begin(), added.end());
    Array nfirst(points + 1), ncorners(corners.size() + added.size()), nheads(ncorners.size());
    each(points + 1, [&](size_t v) {
      const size_t lo = std::lower_bound(added.begin(), added.end(), std::pair<uint32_t, uint32_t>(uint32_t(v), 0)) -
                        added.begin();
      nfirst[v] = first[v] + uint32_t(lo);
      if (v == points) return;
      const uint32_t d = first[v + 1] - first[v];
      std::copy_n(corners.begin() + first[v], d, ncorners.begin() + nfirst[v]);
      std::copy_n(heads.begin() + first[v], d, nheads.begin() + nfirst[v]);
      for (size_t k = lo, at = nfirst[v] + d; k < added.size() && added[k].first == v; ++k, ++at) {
        ncorners[at] = added[k].second;
        nheads[at] = head(added[k].second);
      }
    });
    first = std::move(nfirst);
    corners = std::move(ncorners);
    heads = std::move(nheads);
  }
  // twin[] of the corners at v.
  void twins(uint32_t v) {
    for (uint32_t i = first[v]; i < first[v + 1]; ++i) twin[corners[i]] = edge(heads[i], v);
  }
  // The boundary edges out of a (corners without a twin, twins(a) done): next[a] = the last one's head, then
  // `again(a)` for each one after the first and `into(b)` for each head b.
  template <class Again, class Into>
  void boundary_out(uint32_t a, Array& next, Again&& again, Into&& into) const {
    bool out = false;
    for (uint32_t i = first[a]; i < first[a + 1]; ++i) {
      if (twin[corners[i]] != kNone) continue;
      if (out) again(a);
      out = true;
      next[a] = heads[i];
      into(heads[i]);
    }
  }
  uint32_t degree(uint32_t v) const { return first[v + 1] - first[v]; }
  uint32_t head(uint32_t c) const { return tris[c / 3][(c % 3 + 1) % 3]; }
  uint32_t tail(uint32_t c) const { return tris[c / 3][(c % 3 + 2) % 3]; }
  // The corner at a of the triangle holding the directed edge a -> b, or kNone.
  uint32_t edge(uint32_t a, uint32_t b) const {
    for (uint32_t i = first[a]; i < first[a + 1]; ++i)
      if (heads[i] == b) return corners[i];
    return kNone;
  }
};

struct Checker {
  Geometry g;
  size_t points;
  std::vector<uint32_t>& off;

  // Steps that need a fresh index: each directed edge once, the boundary one simple cycle from the
  // lexicographically smallest vertex (into `cycle`, `next`: the boundary edge out of each vertex).
  bool boundary(Mesh& m, std::vector<uint32_t>& cycle, Array& next) {
    Blame blame;
    set_all(next, points, kNone);
    each(points, [&](size_t v) {
      const uint32_t d = m.degree(uint32_t(v));
      if (d < 2) return;
      uint32_t small[16];
      std::vector<uint32_t> large;
      uint32_t* h = small;
      if (d > 16) {
        large.resize(d);
        h = large.data();
      }
      std::copy(m.heads.begin() + m.first[v], m.heads.begin() + m.first[v + 1], h);
      std::sort(h, h + d);
      for (uint32_t i = 1; i < d; ++i)
        if (h[i] == h[i - 1]) {
          blame.add(uint32_t(v));
          blame.add(h[i]);
        }
    });
    // The smallest used vertex in (x, y) order, the smaller index among equal points (as a serial scan).
    const uint32_t lowest = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, points, kParallelGrain), kNone,
        [&](const tbb::blocked_range<size_t>& r, uint32_t best) {
          for (size_t v = r.begin(); v < r.end(); ++v)
            if (m.degree(uint32_t(v)) && (best == kNone || g.less(uint32_t(v), best))) best = uint32_t(v);
          return best;
        },
        [&](uint32_t a, uint32_t b) {
          if (a == kNone) return b;
          if (b == kNone) return a;
          return g.less(b, a) || (!g.less(a, b) && b < a) ? b : a;
        });
    blame.into(off);
    if (!off.empty()) return false;
    Array in;
    set_all(in, points, 0);
    m.twin.resize(m.tris.size() * 3);
    each(points, [&](size_t v) {
      const uint32_t a = uint32_t(v);
      m.twins(a);
      m.boundary_out(a, next, [&](uint32_t v) { blame.add(v); },
                     [&](uint32_t b) { shared(in[b]).fetch_add(1, std::memory_order_relaxed); });
    });
    each(points, [&](size_t v) {
      if (in[v] > 1 || (in[v] == 1) != (next[v] != kNone)) blame.add(uint32_t(v));
    });
    blame.into(off);
    if (!off.empty() || lowest == kNone) return false;
    if (next[lowest] == kNone) {
      off.push_back(lowest);
      return false;
    }
    cycle.clear();
    std::vector<char> seen(points, 0);
    for (uint32_t v = lowest; !seen[v]; v = next[v]) {
      seen[v] = 1;
      cycle.push_back(v);
    }
    each(points, [&](size_t v) {  // holes and other pieces
      if (next[v] != kNone && !seen[v]) blame.add(uint32_t(v));
    });
    blame.into(off);
    return off.empty();
  }

  // boundary() again after fill(), on the cycle's vertices only: the pockets' triangles have no other corners,
  // and an edge with a twin keeps it, so no other vertex gains a duplicate edge, a boundary edge (after
  // boundary() passed, none has one) or a new twin. The lowest vertex, where the walk starts, is the same.
  bool reboundary(Mesh& m, std::vector<uint32_t>& cycle, Array& next) {
    const std::vector<uint32_t> old = cycle;
    std::vector<uint32_t> h;
    for (uint32_t v : old) {
      h.assign(m.heads.begin() + m.first[v], m.heads.begin() + m.first[v + 1]);
      std::sort(h.begin(), h.end());
      for (size_t i = 1; i < h.size(); ++i)
        if (h[i] == h[i - 1]) off.insert(off.end(), {v, h[i]});
    }
    if (!off.empty()) return false;
    std::unordered_map<uint32_t, uint32_t> in;
    for (uint32_t v : old) next[v] = kNone;
    m.twin.resize(m.tris.size() * 3);
    for (uint32_t a : old) m.twins(a);
    for (uint32_t a : old) m.boundary_out(a, next, [&](uint32_t v) { off.push_back(v); }, [&](uint32_t b) { ++in[b]; });
    for (uint32_t v : old) {
      const uint32_t k = in.count(v) ? in[v] : 0;
      if (k > 1 || (k == 1) != (next[v] != kNone)) off.push_back(v);
    }
    const uint32_t lowest = old[0];
    if (!off.empty()) return false;
    if (next[lowest] == kNone) {
      off.push_back(lowest);
      return false;
    }
    cycle.clear();
    std::unordered_set<uint32_t> seen;
    for (uint32_t v = lowest; seen.insert(v).second; v = next[v]) cycle.push_back(v);
    for (uint32_t v : old)
      if (next[v] != kNone && !seen.count(v)) off.push_back(v);
    return off.empty();
  }

  // Pockets between the boundary and the hull, closed by a Graham scan from the lowest vertex (a hull vertex):
  // a reflex vertex b between a and c gets the triangle (a, c, b). Returns whether it added any.
  bool fill(Mesh& m, const std::vector<uint32_t>& cycle) {
    std::vector<uint32_t> stack;
    const size_t before = m.tris.size();
    for (size_t i = 0; i <= cycle.size(); ++i) {
      const uint32_t c = cycle[i % cycle.size()];
      while (stack.size() >= 2 && g.orient(stack[stack.size() - 2], stack.back(), c) < 0) {
        m.tris.push_back({stack[stack.size() - 2], c, stack.back()});
        stack.pop_back();
      }
      stack.push_back(c);
    }
    return m.tris.size() > before;
  }

  // Every vertex's fan turns once around it (interior) or across its interior angle (boundary).
  void fans(const Mesh& m, const Array& next) {
    Blame blame;
    each(points, [&](size_t vi) {
      const uint32_t v = uint32_t(vi), degree = m.degree(v);
      if (!degree) return;
      const bool on_boundary = next[v] != kNone;
      const uint32_t c0 = on_boundary ? m.edge(v, next[v]) : m.corners[m.first[v]];
      uint32_t c = c0, count = 0, crossings = 0, last = m.head(c0);
      bool closed = false;
      while (count <= degree) {
        ++count;
        const uint32_t b = m.tail(c);  // the triangle (v, last, b) turns from last to b
        crossings += !g.upper(v, last) && g.upper(v, b);
        last = b;
        const uint32_t nc = m.twin[c / 3 * 3 + (c % 3 + 2) % 3];  // edge(v, b): the twin of b -> v
        if (nc == kNone) break;
        if (nc == c0) {
          closed = true;
          break;
        }
        c = nc;
      }
      bool ok = count == degree && closed != on_boundary;
      if (ok && !on_boundary) ok = crossings == 1;
      if (ok && on_boundary) {  // from the outgoing boundary edge v -> a to the incoming p -> v
        const uint32_t a = next[v], p = last;
        const int o = g.orient(v, a, p);
        const bool lower_a = !g.upper(v, a);
        ok = o > 0 ? crossings == uint32_t(lower_a && g.upper(v, p))
                   : o == 0 && g.between(a, v, p) && crossings == uint32_t(lower_a);
      }
      if (!ok) blame.add(v);
    });
    blame.into(off);
  }

  // The boundary convex and winding once.
  void convex(const std::vector<uint32_t>& cycle) {
    const size_t h = cycle.size();
    uint32_t crossings = 0;
    for (size_t i = 0; i < h; ++i) {
      const uint32_t a = cycle[(i + h - 1) % h], b = cycle[i], c = cycle[(i + 1) % h];
      const int o = g.orient(a, b, c);
      if (o < 0 || (o == 0 && !g.between(a, b, c))) off.push_back(b);
      crossings += !g.upper(a, b) && g.upper(b, c);
    }
    if (crossings != 1) off.insert(off.end(), cycle.begin(), cycle.end());
  }
};

StartSlots slots_of(const Mesh& m, const std::vector<uint32_t>& cycle, size_t points) {
  const uint32_t f = uint32_t(m.tris.size()), h = uint32_t(cycle.size());
  StartSlots s;
  s.finite = f;
  s.verts.resize(3 * size_t(f + h));
  s.nbrs.resize(3 * size_t(f + h));
  Array pos;
  set_all(pos, points, kNone);
  for (uint32_t i = 0; i < h; ++i) pos[cycle[i]] = i;
  s.vertices = uint32_t(count_if(points, [&](size_t v) { return m.degree(uint32_t(v)) > 0; }));
  each(f, [&](size_t ti) {
    const uint32_t t = uint32_t(ti);
    for (uint32_t k = 0; k < 3; ++k) {
      s.verts[3 * size_t(t) + k] = m.tris[t][k];
      const uint32_t a = m.tris[t][(k + 1) % 3], c = m.twin[3 * t + (k + 1) % 3];  // edge(b, a) for b -> a
      if (c != kNone) {
        s.nbrs[3 * size_t(t) + k] = NBR(c / 3, (c % 3 + 2) % 3);
        continue;
      }
      const uint32_t inf = f + pos[a];  // (b, a, INF): its edge 2 is b -> a; one finite edge each
      s.nbrs[3 * size_t(t) + k] = NBR(inf, 2u);
      s.nbrs[3 * size_t(inf) + 2] = NBR(t, k);
    }
  });
  for (uint32_t i = 0; i < h; ++i) {
    const uint32_t inf = f + i;
    s.verts[3 * size_t(inf)] = cycle[(i + 1) % h];
    s.verts[3 * size_t(inf) + 1] = cycle[i];
    s.verts[3 * size_t(inf) + 2] = INF_VERTEX;
    s.nbrs[3 * size_t(inf)] = NBR(f + (i + h - 1) % h, 1u);  // a -> INF meets INF -> a of the edge before
    s.nbrs[3 * size_t(inf) + 1] = NBR(f + (i + 1) % h, 0u);
  }
  s.slot_of.resize(points);
  each(points, [&](size_t v) {  // the last finite slot at v, as a serial pass in slot order would leave
    s.slot_of[v] = m.first[v + 1] > m.first[v] ? m.corners[m.first[v + 1] - 1] / 3 : kNone;
  });
  return s;
}

}  // namespace

std::optional<StartSlots> dual_to_slots(std::span<const double> xy, RawVector<Triangle> tris,
                                        std::vector<uint32_t>& offenders, bool oriented) {
  const size_t points = xy.size() / 2;
  offenders.clear();
  Checker ck{Geometry{xy}, points, offenders};
  auto fail = [&]() -> std::optional<StartSlots> {
    std::sort(offenders.begin(), offenders.end());
    offenders.erase(std::unique(offenders.begin(), offenders.end()), offenders.end());
    return std::nullopt;
  };
  tris = normalise(std::move(tris), points);
  Blame blame;
  each(tris.size(), [&](size_t i) {
    const Triangle& t = tris[i];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (!oriented && ck.g.orient(t[0], t[1], t[2]) <= 0))
      for (uint32_t v : t) blame.add(v);
  });
  blame.into(offenders);
  if (!offenders.empty() || tris.empty()) return fail();
  Mesh m;
  m.tris = std::move(tris);
  m.index(points);
  std::vector<uint32_t> cycle;
  Array next;
  if (!ck.boundary(m, cycle, next)) return fail();
  const size_t before = m.tris.size();
  if (ck.fill(m, cycle)) {  // fill triangles are counter-clockwise by construction (a reflex turn reversed)
    m.reindex(before, points);
    if (!ck.reboundary(m, cycle, next)) return fail();
  }
  ck.fans(m, next);
  ck.convex(cycle);
  if (!offenders.empty()) return fail();
  const uint64_t vertices = count_if(points, [&](size_t v) { return m.degree(uint32_t(v)) > 0; });
  const uint64_t f = m.tris.size(), edges = (3 * f + cycle.size()) / 2;
  if (vertices + f != edges + 1) return fail();  // Euler: a disc (no repair known)
  return slots_of(m, cycle, points);
}

}  // namespace cdtgpu::gpu
