// apply_regions: boundaries, holes and max-edge trimming over a finished CDT, on all cores. Cost: O(T) work
// in parallel passes: the twins of the 3T half-edges, one walk per constraint along mesh edges, union-find
// over triangle adjacency, a breadth-first search over its few components, one compaction. Every pass gives
// the same result whatever the thread count or schedule: flags are combined by OR and XOR, the walk breaks
// ties by vertex id, a set's root is its smallest triangle.
//
// The constrained mesh edges are found the way verify.cpp finds them: from one end of a constraint, step to
// the neighbour that lies on the segment (exact orientation for input vertices; within rounding for Steiner
// vertices, which are rounded crossings and generally just off the segment) and is nearest along it.
#include "core/regions.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cfloat>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/big_array.hpp"
#include "core/error.hpp"
#include "core/half_edges.hpp"
#include "core/parallel.hpp"

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint8_t kConstrained = 1, kRegion = 2;
constexpr size_t kGrain = 1 << 14;

uint64_t key(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

bool xy_less(const Point3& a, const Point3& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; }

// Index of the vertex at (x, y) in vertices sorted by (x, y), or kNone.
uint32_t find_vertex(const Points& vs, const Point3& p) {
  auto it = std::lower_bound(vs.begin(), vs.end(), p, xy_less);
  return it != vs.end() && it->x == p.x && it->y == p.y ? uint32_t(it - vs.begin()) : kNone;
}

// Marks the mesh edges along the constraints: kConstrained, plus kRegion for region edges. Without `all`, only
// the region edges (the nesting levels need no other; trimming needs every constraint): a boundary and a hole
// over 500K contour segments walk 1K segments, not 500K.
// mesh_of[i]: the mesh vertex of prepared vertex i; is_input[m], if asked for: whether mesh vertex m is one of
// them (the others are Steiner vertices).
void mesh_vertices_of(const Mesh& mesh, const PreparedInput& prepared, BigArray<uint32_t>& mesh_of,
                      BigArray<uint8_t>* is_input = nullptr) {
  const Points& mv = mesh.vertices;
  const uint32_t V = uint32_t(mv.size());
  if (is_input) *is_input = BigArray<uint8_t>(V, 0);
  mesh_of = BigArray<uint32_t>(prepared.vertices.size());
  // Both vertex lists are sorted by (x, y): each block finds its first vertex by bisection, then merges.
  std::atomic<size_t> missing{SIZE_MAX};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, prepared.vertices.size(), kGrain),
                    [&](const tbb::blocked_range<size_t>& r) {
                      uint32_t m = uint32_t(std::lower_bound(mv.begin(), mv.end(), prepared.vertices[r.begin()],
                                                             xy_less) - mv.begin());
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        const Point3& p = prepared.vertices[i];
                        while (m < V && xy_less(mv[m], p)) ++m;
                        if (m == V || mv[m].x != p.x || mv[m].y != p.y) {
                          size_t first_missing = missing.load();
                          while (i < first_missing && !missing.compare_exchange_weak(first_missing, i)) {
                          }
                          return;
                        }
                        mesh_of[i] = m;
                        if (is_input) (*is_input)[m] = 1;  // input vertices are distinct: one writer per byte
                      }
                    });
  if (missing != SIZE_MAX)
    throw std::logic_error("regions: input vertex " + std::to_string(missing.load()) + " is not in the mesh");
}

void mark_constraints(const Mesh& mesh, const PreparedInput& prepared, const std::vector<uint8_t>& region,
                      bool all, const HalfEdges& e, BigArray<uint8_t>& flag) {
  const Points& mv = mesh.vertices;
  const uint32_t V = uint32_t(mv.size());
  auto P = [&](uint32_t v) { return P2(mv[v].x, mv[v].y); };
  BigArray<uint8_t> is_input;
  BigArray<uint32_t> mesh_of;
  mesh_vertices_of(mesh, prepared, mesh_of, &is_input);

  std::atomic<size_t> uncovered{SIZE_MAX};  // the smallest failing constraint, whatever the schedule
  each(prepared.constraints.size(), [&](size_t c) {
    // Region edges toggle: a mesh edge covered by two region segments (collinear overlaps) is crossed twice.
    const uint8_t toggle = c < region.size() && region[c] ? kRegion : 0;
    if (!all && !toggle) return;
    const uint32_t A = mesh_of[prepared.constraints[c][0]], B = mesh_of[prepared.constraints[c][1]];
    const P2 pa = P(A), pb = P(B);
    const double ux = pb.x() - pa.x(), uy = pb.y() - pa.y();
    const double len2 = ux * ux + uy * uy, len = std::sqrt(len2);
    const double mag = std::max({std::abs(pa.x()), std::abs(pa.y()), std::abs(pb.x()), std::abs(pb.y())});
    const double tol = 1e-9 * len + 8 * DBL_EPSILON * mag;  // rounding: of Steiner vertices, of merged crossings
    // 0: exactly on the open segment; 1: within rounding of it; 2: neither.
    auto on_segment = [&](uint32_t w) {
      const P2 pw = P(w);
      if (CGAL::orientation(pa, pb, pw) == CGAL::COLLINEAR)
        return CGAL::collinear_are_strictly_ordered_along_line(pa, pw, pb) ? 0 : 2;
      const double wx = pw.x() - pa.x(), wy = pw.y() - pa.y();
      const double along = wx * ux + wy * uy;
      return std::abs(wx * uy - wy * ux) <= tol * len && along > 0 && along < len2 ? 1 : 2;
    };
    auto along = [&](uint32_t w) { return (mv[w].x - pa.x()) * ux + (mv[w].y - pa.y()) * uy; };
    // The fan around v: turn one way through twins of the previous half-edges; at the hull, take the hull
    // half-edge ending at v and turn the other way from the start. visit(w, half-edge between v and w).
    auto fan = [&](uint32_t v, auto&& visit) {
      const uint32_t h0 = e.corner[v];
      uint32_t h = h0;
      bool hull = false;
      do {
        visit(to_of(mesh.triangles, h), h);
        const uint32_t p = prev_of(h);
        if (e.twin[p] == kNone) {
          visit(from_of(mesh.triangles, p), p);
          hull = true;
          break;
        }
        h = e.twin[p];
      } while (h != h0);
      for (h = h0; hull && e.twin[h] != kNone;) {
        h = next_of(e.twin[h]);
        visit(to_of(mesh.triangles, h), h);
      }
    };
    thread_local std::vector<uint32_t> path;  // the half-edges along the constraint
    path.clear();
    // The walk: from each vertex, the nearest one further along that is on the segment (input vertices
    // exactly, Steiner vertices within rounding).
    auto walk = [&] {
      for (uint32_t cur = A, steps = 0; cur != B; ++steps) {
        uint32_t best = kNone, best_he = kNone;
        double best_along = HUGE_VAL;
        fan(cur, [&](uint32_t w, uint32_t h) {
          if (best == B) return;
          if (w == B) {
            best = w, best_he = h;
            return;
          }
          const double a = (mv[w].x - mv[cur].x) * ux + (mv[w].y - mv[cur].y) * uy;
          if (a > 0 && (a < best_along || (a == best_along && w < best))) {
            const int kind = on_segment(w);
            if (kind == 0 || (kind == 1 && !is_input[w])) best = w, best_he = h, best_along = a;
          }
        });
        if (best == kNone || steps > V) return false;
        path.push_back(best_he);
        cur = best;
      }
      return true;
    };
    // Where the walk stops: a crossing that rounded onto an input vertex beside the constraint (docs/rules.md),
    // or a cascade of rounded crossings. The path through the fewest vertices not exactly on the segment, input
    // ones too (a 0-1 search). A step may go back along the segment by rounding: rounded crossings beside it
    // need not lie in the order of the exact ones (a vertex is queued again only for a cheaper path: it ends).
    auto search = [&] {
      path.clear();
      struct Node {
        uint32_t cost, prev, he;
      };
      std::unordered_map<uint32_t, Node> seen{{A, {0, kNone, kNone}}};
      std::deque<uint32_t> queue{A};
      while (!queue.empty()) {
        const uint32_t u = queue.front();
        queue.pop_front();
        if (u == B) {
          for (uint32_t w = B; w != A; w = seen[w].prev) path.push_back(seen[w].he);
          return true;
        }
        const uint32_t cu = seen[u].cost;
        const double au = along(u);
        fan(u, [&](uint32_t w, uint32_t h) {
          const int kind = w == B ? 0 : along(w) > au - tol * len ? on_segment(w) : 2;
          if (kind == 2) return;
          const uint32_t cw = cu + uint32_t(kind);
          auto [it, fresh] = seen.try_emplace(w, Node{cw, u, h});
          if (!fresh && it->second.cost <= cw) return;
          it->second = {cw, u, h};
          kind == 0 ? queue.push_front(w) : queue.push_back(w);
        });
      }
      return false;
    };
    if (!walk() && !search()) {
      size_t m = uncovered.load();
      while (c < m && !uncovered.compare_exchange_weak(m, c)) {
      }
      return;
    }
    for (const uint32_t step : path)
      for (uint32_t h : {step, e.twin[step]}) {
        if (h == kNone) continue;
        shared(flag[h]).fetch_or(kConstrained, std::memory_order_relaxed);
        if (toggle) shared(flag[h]).fetch_xor(toggle, std::memory_order_relaxed);
      }
  });
  if (uncovered != SIZE_MAX)
    throw std::logic_error("regions: constraint " + std::to_string(uncovered.load()) +
                           " is not covered by mesh edges (the mesh is not the CDT of its input)");
}

// Concurrent union-find over triangles: a set's root is its smallest member (the larger root is linked under
// the smaller one), so the sets and their roots do not depend on the order of the unions.
class Forest {
 public:
  explicit Forest(size_t n) : parent_(n) {}
  // Makes [begin, end) singletons: every element is set by some init before the unions.
  void init(size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) parent_[i] = uint32_t(i);
  }
  uint32_t find(uint32_t x) {
    for (;;) {
      const uint32_t p = shared(parent_[x]).load(std::memory_order_relaxed);
      if (p == x) return x;
      const uint32_t g = shared(parent_[p]).load(std::memory_order_relaxed);
      if (g != p) shared(parent_[x]).store(g, std::memory_order_relaxed);  // path halving: g is an ancestor
      x = g;
    }
  }
  void unite(uint32_t a, uint32_t b) {
    for (;;) {
      a = find(a), b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      uint32_t expected = a;
      if (shared(parent_[a]).compare_exchange_weak(expected, b, std::memory_order_relaxed)) return;
    }
  }
  // unite for a block of elements that only one thread touches for now: plain loads and stores.
  void unite_alone(uint32_t a, uint32_t b) {
    a = find_alone(a), b = find_alone(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }
  // Every member's root, once the unions are done, in place of the links (a root is an ancestor too).
  BigArray<uint32_t> roots() && {
    each(parent_.size(),
         [&](size_t i) { shared(parent_[i]).store(find(uint32_t(i)), std::memory_order_relaxed); });
    return std::move(parent_);
  }

 private:
  uint32_t find_alone(uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  BigArray<uint32_t> parent_;
};

// Roots of the triangles joined across the half-edges h with joined(h); hull(h) is called for each hull
// half-edge, apart(h) for each edge not joined (once, from its smaller triangle). Blocks of triangles are
// joined inside on one thread each, without atomics: most pairs are, neighbours being near in the canonical
// order. The pairs across blocks then join on all cores.
template <class F, class G, class A>
BigArray<uint32_t> components(const HalfEdges& e, size_t T, F&& joined, G&& hull, A&& apart) {
  constexpr size_t kBlock = 1 << 16;
  Forest forest(T);
  tbb::enumerable_thread_specific<std::vector<uint64_t>> across_local;
  tbb::parallel_for(size_t(0), (T + kBlock - 1) / kBlock, [&](size_t b) {
    const size_t t0 = b * kBlock, t1 = std::min(T, t0 + kBlock);
    forest.init(t0, t1);
    auto& across = across_local.local();
    for (size_t t = t0; t < t1; ++t)
      for (size_t h = 3 * t; h < 3 * t + 3; ++h) {
        const uint32_t u = e.twin[h] == kNone ? kNone : e.twin[h] / 3;
        if (u == kNone)
          hull(h);
        else if (u > t && !joined(h))
          apart(h);
        else if (u > t)
          u < t1 ? forest.unite_alone(uint32_t(t), u) : across.push_back(key(uint32_t(t), u));
      }
  });
  for (auto& v : across_local)
    each(v.size(), [&](size_t i) { forest.unite(uint32_t(v[i] >> 32), uint32_t(v[i])); });
  return std::move(forest).roots();
}

// Nesting levels: 0 for the triangles reached from beyond the hull without crossing a region edge, +1 for
// each region edge crossed (CGAL's mark_domains). Triangles joined by other edges share their level, so the
// breadth-first search runs over the components only: triangle t's level is level_of_root[root[t]].
struct Levels {
  BigArray<uint32_t> root, level_of_root;
};
Levels nesting_levels(const HalfEdges& e, size_t T, const BigArray<uint8_t>& flag) {
  // The hull's half-edges and the region edges (few), by triangle, as the components are found.
  tbb::enumerable_thread_specific<std::vector<uint64_t>> hull_local, region_local;
  BigArray<uint32_t> root = components(
      e, T, [&](size_t h) { return !(flag[h] & kRegion); },
      [&](size_t h) { hull_local.local().push_back(key(uint32_t(h / 3), (flag[h] & kRegion) != 0)); },
      [&](size_t h) { region_local.local().push_back(key(uint32_t(h / 3), e.twin[h] / 3)); });
  // Crossings between components, both ways, and the hull's entries: (component, 1) across a region edge,
  // (component, 0) otherwise.
  std::vector<uint64_t> cross, entry;
  for (const auto& v : hull_local)
    for (uint64_t k : v) entry.push_back(key(root[k >> 32], uint32_t(k)));
  for (const auto& v : region_local)
    for (uint64_t k : v)
      if (const uint32_t a = root[k >> 32], b = root[uint32_t(k)]; a != b) {
        cross.push_back(key(a, b));
        cross.push_back(key(b, a));
      }
  tbb::parallel_sort(cross.begin(), cross.end());
  std::sort(entry.begin(), entry.end());

  // 0-1 breadth-first search from the outside, by component root. Every root is in an entry or a crossing
  // (the mesh is connected): only those elements are set, and read.
  BigArray<uint32_t> level_of_root(T);
  for (uint64_t k : entry) level_of_root[k >> 32] = kNone;
  for (uint64_t k : cross) level_of_root[k >> 32] = kNone;
  std::deque<uint32_t> queue;
  for (uint64_t k : entry) {
    const uint32_t a = uint32_t(k >> 32), L = uint32_t(k & 1);
    if (level_of_root[a] != kNone && level_of_root[a] <= L) continue;
    level_of_root[a] = L;
    L == 0 ? queue.push_front(a) : queue.push_back(a);
  }
  while (!queue.empty()) {
    const uint32_t a = queue.front();
    queue.pop_front();
    auto it = std::lower_bound(cross.begin(), cross.end(), key(a, 0));
    for (; it != cross.end() && uint32_t(*it >> 32) == a; ++it) {
      const uint32_t b = uint32_t(*it);
      if (level_of_root[b] > level_of_root[a] + 1) {
        level_of_root[b] = level_of_root[a] + 1;
        queue.push_back(b);
      }
    }
  }
  return {std::move(root), std::move(level_of_root)};
}

// keep[t] for every triangle by its nesting level: odd levels are inside, or even ones if outside_kept.
// Returns how many are not kept.
uint64_t keep_inside(const HalfEdges& e, size_t T, const BigArray<uint8_t>& flag, bool outside_kept,
                     BigArray<uint8_t>& keep) {
  const Levels l = nesting_levels(e, T, flag);
  // Every triangle is reached (the mesh is connected); kNone would count as odd.
  return count_if(T, [&](size_t t) {
    keep[t] = (l.level_of_root[l.root[t]] % 2 == 1) != outside_kept;
    return !keep[t];
  });
}

// Drops from keep the triangles reached from beyond the hull across unconstrained edges longer than max_edge
// (the components, joined by such edges, of the triangles with such an edge on the hull); returns how many.
uint64_t trim(const Mesh& mesh, const HalfEdges& e, const BigArray<uint8_t>& flag, double max_edge,
              BigArray<uint8_t>& keep) {
  const size_t T = mesh.triangles.size();
  const double limit2 = max_edge * max_edge;
  auto long_open = [&](size_t h) {
    if (flag[h] & kConstrained) return false;
    const Point3 &a = mesh.vertices[mesh.triangles[h / 3][h % 3]],
                 &b = mesh.vertices[mesh.triangles[h / 3][(h % 3 + 1) % 3]];
    const double dx = b.x - a.x, dy = b.y - a.y;
    return dx * dx + dy * dy > limit2;
  };
  tbb::enumerable_thread_specific<std::vector<uint32_t>> seeds;
  auto seed_of = [&](size_t h) {
    if (long_open(h)) seeds.local().push_back(uint32_t(h / 3));
  };
  const BigArray<uint32_t> root = components(e, T, long_open, seed_of, [](size_t) {});
  BigArray<uint8_t> seed(T, 0);
  for (const auto& v : seeds)
    for (uint32_t t : v) seed[root[t]] = 1;
  return count_if(T, [&](size_t t) {
    const bool drop = keep[t] && seed[root[t]];
    if (drop) keep[t] = 0;
    return drop;
  });
}

// --max-edge alone (no boundary or hole): a trimmed triangle is entered across one of its edges, so it has a
// long one, and only the long half-edges need pairing (a sort of them, not the twins of every half-edge). A
// constraint stops the trimming on the long mesh edges along it, which are its own edge when every long
// constraint is one mesh edge. Returns the trimmed triangles, in order; nullopt when this
// path does not apply (a long constraint split by vertices on it, or so many long edges that pairing them all
// is the general path's work): the caller then takes that path, which walks the constraints.
std::optional<std::vector<uint32_t>> trim_long_edges(const Mesh& mesh, const PreparedInput& prepared,
                                                     double max_edge) {
  const Triangles& ts = mesh.triangles;
  const Points& mv = mesh.vertices;
  const size_t T = ts.size();
  const double limit2 = max_edge * max_edge;
  auto is_long = [&](uint32_t a, uint32_t b) {
    const double dx = mv[b].x - mv[a].x, dy = mv[b].y - mv[a].y;
    return dx * dx + dy * dy > limit2;  // the same either way round: the general path's test
  };
  tbb::enumerable_thread_specific<std::vector<HalfEdgeKey>> local;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, T, kGrain), [&](const tbb::blocked_range<size_t>& r) {
    auto& mine = local.local();
    for (size_t t = r.begin(); t < r.end(); ++t)
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = ts[t][k], b = ts[t][(k + 1) % 3];
        if (is_long(a, b)) mine.push_back({key(std::min(a, b), std::max(a, b)), uint32_t(3 * t + k)});
      }
  });
  std::vector<HalfEdgeKey> longs;
  for (auto& v : local) {
    if (longs.size() + v.size() > T / 4) return std::nullopt;  // pairing them all: the general path's work
    longs.insert(longs.end(), v.begin(), v.end());
  }
  tbb::parallel_sort(longs.begin(), longs.end());
  auto is_mesh_edge = [&](uint64_t edge) {
    const auto it = std::lower_bound(longs.begin(), longs.end(), HalfEdgeKey{edge, 0});
    return it != longs.end() && it->edge == edge;
  };

  // The long constraints, each of which must be a mesh edge.
  BigArray<uint32_t> mesh_of;
  mesh_vertices_of(mesh, prepared, mesh_of);
  tbb::enumerable_thread_specific<std::vector<uint64_t>> long_constraints;
  std::atomic<bool> split{false};
  each(prepared.constraints.size(), [&](size_t c) {
    const uint32_t a = mesh_of[prepared.constraints[c][0]], b = mesh_of[prepared.constraints[c][1]];
    if (!is_long(a, b)) return;
    const uint64_t edge = key(std::min(a, b), std::max(a, b));
    if (is_mesh_edge(edge))
      long_constraints.local().push_back(edge);
    else
      split.store(true, std::memory_order_relaxed);
  });
  if (split) return std::nullopt;
  std::vector<uint64_t> constrained;
  for (const auto& v : long_constraints) constrained.insert(constrained.end(), v.begin(), v.end());
  tbb::parallel_sort(constrained.begin(), constrained.end());

  // The triangles with a long open edge, joined across such edges; those with one on the hull are seeds.
  std::vector<uint32_t> cand;  // sorted triangle ids
  std::vector<std::array<uint32_t, 2>> joins;
  std::vector<uint32_t> seeds;
  for (size_t i = 0; i < longs.size();) {
    size_t j = i + 1;
    while (j < longs.size() && longs[j].edge == longs[i].edge) ++j;
    if (j - i > 2) throw std::logic_error("regions: a mesh edge with more than two triangles");
    if (!std::binary_search(constrained.begin(), constrained.end(), longs[i].edge)) {
      for (size_t k = i; k < j; ++k) cand.push_back(longs[k].h / 3);
      if (j - i == 1)
        seeds.push_back(longs[i].h / 3);
      else
        joins.push_back({longs[i].h / 3, longs[i + 1].h / 3});
    }
    i = j;
  }
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  auto index = [&](uint32_t t) { return uint32_t(std::lower_bound(cand.begin(), cand.end(), t) - cand.begin()); };
  Forest forest(cand.size());  // over the candidates' indices
  forest.init(0, cand.size());
  for (const auto& [t, u] : joins) forest.unite_alone(index(t), index(u));
  const BigArray<uint32_t> root = std::move(forest).roots();
  std::vector<uint8_t> seeded(cand.size(), 0);
  for (uint32_t t : seeds) seeded[root[index(t)]] = 1;
  std::vector<uint32_t> trimmed;
  for (uint32_t i = 0; i < cand.size(); ++i)
    if (seeded[root[i]]) trimmed.push_back(cand[i]);
  return trimmed;
}

// The items of `in` but those at the sorted indices `removed`, each through `map`, in order: block by block,
// each block at its start less the removed before it.
template <class T, class F>
RawVector<T> without(const RawVector<T>& in, const std::vector<uint32_t>& removed, F&& map) {
  constexpr size_t kBlock = 1 << 16;
  const size_t n = in.size();
  RawVector<T> out;
  resize_unwritten(out, n - removed.size());
  tbb::parallel_for(size_t(0), (n + kBlock - 1) / kBlock, [&](size_t b) {
    const size_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    auto r = std::lower_bound(removed.begin(), removed.end(), uint32_t(i0));
    size_t at = i0 - size_t(r - removed.begin());
    for (size_t i = i0; i < i1; ++i) {
      if (r != removed.end() && *r == i) {
        ++r;
        continue;
      }
      out[at++] = map(in[i]);
    }
  });
  return out;
}

// Drops the few triangles `dropped` (in order) and the vertices left in no triangle. Only their corners can be
// left so: each is counted among all triangles and among the dropped. Both lists keep their order and the
// renumbering is monotone, so the mesh stays canonical. Returns how many vertices went.
uint64_t drop_few(Mesh& mesh, const std::vector<uint32_t>& dropped) {
  Triangles& ts = mesh.triangles;
  const size_t T = ts.size(), V = mesh.vertices.size();
  std::vector<uint32_t> corners;
  for (uint32_t t : dropped) corners.insert(corners.end(), ts[t].begin(), ts[t].end());
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  std::vector<uint64_t> is_corner((V + 63) / 64, 0);
  for (uint32_t v : corners) is_corner[v / 64] |= uint64_t(1) << (v % 64);
  auto index = [&](uint32_t v) { return size_t(std::lower_bound(corners.begin(), corners.end(), v) - corners.begin()); };
  std::vector<std::atomic<uint32_t>> in_all(corners.size());
  std::vector<uint32_t> in_dropped(corners.size(), 0);
  for (uint32_t t : dropped)
    for (uint32_t v : ts[t]) ++in_dropped[index(v)];
  each(T, [&](size_t t) {
    for (uint32_t v : ts[t])
      if (is_corner[v / 64] >> (v % 64) & 1) in_all[index(v)].fetch_add(1, std::memory_order_relaxed);
  });
  std::vector<uint32_t> gone;  // vertices left in no triangle, in order
  for (size_t i = 0; i < corners.size(); ++i)
    if (in_all[i].load() == in_dropped[i]) gone.push_back(corners[i]);
  auto renumber = [&](uint32_t v) {
    return gone.empty() ? v : v - uint32_t(std::upper_bound(gone.begin(), gone.end(), v) - gone.begin());
  };
  ts = without(ts, dropped, [&](const Triangle& t) { return Triangle{renumber(t[0]), renumber(t[1]), renumber(t[2])}; });
  if (!gone.empty()) mesh.vertices = without(mesh.vertices, gone, [](const Point3& p) { return p; });
  return gone.size();
}

// used[v]: whether v is a corner of a kept triangle. Each vertex is written by one thread, or marks from
// every thread would share cache lines: the triangles starting in a block of vertices mark their corners in
// that block (a corner is never below the start) and leave the few beyond it to a second pass.
BigArray<uint8_t> used_vertices(const Triangles& ts, const HalfEdges& e,
                                const BigArray<uint8_t>& keep) {
  constexpr size_t kBlock = 1 << 16;
  const size_t V = e.start.size() - 1;
  BigArray<uint8_t> used(V);
  tbb::enumerable_thread_specific<std::vector<uint32_t>> beyond_local;
  tbb::parallel_for(size_t(0), (V + kBlock - 1) / kBlock, [&](size_t b) {
    const size_t v0 = b * kBlock, v1 = std::min(V, v0 + kBlock);
    std::fill(used.begin() + v0, used.begin() + v1, 0);
    auto& beyond = beyond_local.local();
    for (size_t t = e.start[v0]; t < e.start[v1]; ++t)
      if (keep[t])
        for (uint32_t v : ts[t]) v < v1 ? void(used[v] = 1) : beyond.push_back(v);
  });
  for (const auto& v : beyond_local)
    each(v.size(), [&](size_t i) { shared(used[v[i]]).store(1, std::memory_order_relaxed); });
  return used;
}

// The used vertices, in order, and renumber[v], each one's new index (kNone for the others).
Points kept_vertices(const Mesh& mesh, const BigArray<uint8_t>& used,
                                  BigArray<uint32_t>& renumber) {
  constexpr size_t kBlock = 1 << 16;
  const size_t V = mesh.vertices.size(), blocks = (V + kBlock - 1) / kBlock;
  auto end = [&](size_t b) { return std::min(V, (b + 1) * kBlock); };
  std::vector<uint32_t> first(blocks + 1, 0);  // first[b + 1]: block b's count, then the offsets
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t n = 0;
    for (size_t v = b * kBlock; v < end(b); ++v) renumber[v] = used[v] ? n++ : kNone;
    first[b + 1] = n;
  });
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  Points out;
  resize_unwritten(out, first[blocks]);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    for (size_t v = b * kBlock; v < end(b); ++v)
      if (renumber[v] != kNone) out[renumber[v] += first[b]] = mesh.vertices[v];
  });
  return out;
}

// Keeps the triangles with keep[t], renumbered, at the front of `ts`, and drops the rest. They go through
// `scratch` (3 per triangle: the twins' pages, faulted already) and back into ts' own pages: a fresh list
// would fault its pages, and freeing the old one unmap them.
void keep_triangles(Triangles& ts, const BigArray<uint8_t>& keep,
                    const BigArray<uint32_t>& renumber, BigArray<uint32_t>& scratch) {
  constexpr size_t kBlock = 1 << 16;
  const size_t T = ts.size(), blocks = (T + kBlock - 1) / kBlock;
  auto end = [&](size_t b) { return std::min(T, (b + 1) * kBlock); };
  std::vector<size_t> first(blocks + 1, 0);  // first[b + 1]: block b's count, then the offsets
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    size_t n = 0;
    for (size_t t = b * kBlock; t < end(b); ++t) n += keep[t];
    first[b + 1] = n;
  });
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    uint32_t* at = scratch.begin() + 3 * first[b];
    for (size_t t = b * kBlock; t < end(b); ++t)
      if (keep[t])
        for (uint32_t v : ts[t]) *at++ = renumber[v];
  });
  each(first[blocks], [&](size_t k) { ts[k] = {scratch[3 * k], scratch[3 * k + 1], scratch[3 * k + 2]}; });
  ts.resize(first[blocks]);
}

}  // namespace

std::vector<uint8_t> region_constraints(const PreparedInput& prepared, const std::vector<Polyline>& rings) {
  // Each ring's segments, by the ends' vertex ids (smaller first); a segment whose ends are not both input
  // vertices is no constraint and is left out (0).
  std::vector<size_t> start(rings.size() + 1, 0);
  for (size_t i = 0; i < rings.size(); ++i) {
    const Polyline& l = rings[i];
    const size_t n = l.points.size();
    start[i + 1] = start[i] + (n < 2 ? 0 : (l.closed && n >= 3 ? n : n - 1));
  }
  std::vector<uint64_t> segs(start.back(), 0);
  tbb::parallel_for(size_t(0), rings.size(), [&](size_t i) {
    const Polyline& l = rings[i];
    const size_t n = l.points.size();
    for (size_t k = 0; k < start[i + 1] - start[i]; ++k) {
      uint32_t a = find_vertex(prepared.vertices, l.points[k]);
      uint32_t b = find_vertex(prepared.vertices, l.points[(k + 1) % n]);
      if (a == kNone || b == kNone || a == b) continue;
      if (a > b) std::swap(a, b);
      segs[start[i] + k] = key(a, b);
    }
  });
  tbb::parallel_sort(segs.begin(), segs.end());
  // A segment given by two rings (adjacent parcels, a lake on the boundary) is crossed twice: no region edge.
  std::vector<uint8_t> region(prepared.constraints.size(), 0);
  each(region.size(), [&](size_t c) {
    const uint64_t k = key(prepared.constraints[c][0], prepared.constraints[c][1]);
    region[c] =
        (std::upper_bound(segs.begin(), segs.end(), k) - std::lower_bound(segs.begin(), segs.end(), k)) % 2;
  });
  return region;
}

RegionRules region_rules(const InputSet& in, const std::vector<InputPart>& parts,
                         const PreparedInput& prepared, double max_edge) {
  std::vector<Polyline> rings;
  bool boundary = false;
  for (const InputPart& part : parts) {
    if (!is_region_role(part.role)) continue;
    for (size_t i = part.lines_begin; i < part.lines_end; ++i) rings.push_back(in.lines[i]);
    boundary |= part.role == Role::boundary && part.lines_end > part.lines_begin;
  }
  RegionRules rules;
  if (!rings.empty()) rules.region_edge = region_constraints(prepared, rings);
  rules.outside_kept = !boundary;
  rules.max_edge = max_edge;
  return rules;
}

OpenEnds open_region_ends(const PreparedInput& prepared, const RegionRules& rules) {
  // Both ends of every region edge, sorted: a byte a vertex would cost every run (1.25 GB at 1B points).
  std::vector<uint32_t> ends;
  for (size_t c = 0; c < prepared.constraints.size() && c < rules.region_edge.size(); ++c)
    if (rules.region_edge[c]) ends.insert(ends.end(), prepared.constraints[c].begin(), prepared.constraints[c].end());
  std::sort(ends.begin(), ends.end());
  OpenEnds open;
  for (size_t i = 0, j = 0; i < ends.size(); i = j) {
    while (j < ends.size() && ends[j] == ends[i]) ++j;
    if ((j - i) % 2 && open.count++ == 0) open.first = ends[i];
  }
  return open;
}

std::string open_ends_text(const PreparedInput& prepared, const OpenEnds& open) {
  const Point3& p = prepared.vertices[open.first];
  return "boundary and hole lines do not close (" + std::to_string(open.count) + " open ends, the first at (" +
         number_text(p.x) + ", " + number_text(p.y) + "))";
}

RegionStats apply_regions(Mesh& mesh, const PreparedInput& prepared, const RegionRules& rules) {
  RegionStats stats;
  const size_t T = mesh.triangles.size(), V = mesh.vertices.size();
  const bool regions =
      std::find(rules.region_edge.begin(), rules.region_edge.end(), 1) != rules.region_edge.end();
  if (T == 0 || (!regions && rules.max_edge <= 0)) return stats;
  // Half-edges are numbered in 32 bits.
  if (3 * uint64_t(T) >= kNone)
    throw UsageError("boundaries, holes and --max-edge take meshes of at most " + std::to_string(kNone / 3 - 1) +
                     " triangles; this one has " + std::to_string(T) +
                     ": leave them out, or split the input into parts");
  // Pass times for -v: what to look at when the stage grows.
  auto t0 = std::chrono::steady_clock::now();
  std::string passes;
  auto lap = [&](const char* name) {
    const auto t = std::chrono::steady_clock::now();
    passes += fmt::format(" {} {:.1f} ms", name, std::chrono::duration<double, std::milli>(t - t0).count());
    t0 = t;
  };
  if (!regions)
    if (const std::optional<std::vector<uint32_t>> trimmed = trim_long_edges(mesh, prepared, rules.max_edge)) {
      lap("long edges");
      stats.triangles_trimmed = trimmed->size();
      if (!trimmed->empty()) {
        stats.vertices_removed = drop_few(mesh, *trimmed);
        lap("compaction");
      }
      spdlog::debug("regions:{}", passes);
      return stats;
    }
  HalfEdges e = half_edges(mesh.triangles, uint32_t(mesh.vertices.size()));
  lap("half-edges");
  BigArray<uint8_t> flag(3 * T, 0);
  mark_constraints(mesh, prepared, rules.region_edge, rules.max_edge > 0, e, flag);
  lap("constraints");

  BigArray<uint8_t> keep = regions ? BigArray<uint8_t>(T) : BigArray<uint8_t>(T, 1);
  if (regions) {
    stats.triangles_outside = keep_inside(e, T, flag, rules.outside_kept, keep);
    lap("levels");
  }
  if (rules.max_edge > 0) {
    stats.triangles_trimmed = trim(mesh, e, flag, rules.max_edge, keep);
    lap("trim");
  }

  // Compaction: the vertices still used, then the kept triangles. The renumbering keeps the order of
  // vertices, so triangles stay sorted and start at their smallest index: the mesh stays canonical.
  BigArray<uint32_t> renumber(V);
  Points vertices = kept_vertices(mesh, used_vertices(mesh.triangles, e, keep), renumber);
  keep_triangles(mesh.triangles, keep, renumber, e.twin);
  stats.vertices_removed = V - vertices.size();
  mesh.vertices = std::move(vertices);
  lap("compaction");
  spdlog::debug("regions:{}", passes);
  return stats;
}

}  // namespace cdtgpu
