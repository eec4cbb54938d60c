#include "gpu/voronoi_check.hpp"

#include <algorithm>

#include "core/predicates.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

constexpr uint32_t kNone = UINT32_MAX;

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

// Triangles and, per vertex, its corners (3t + j), each the start of the directed edge t[j] -> t[j + 1].
struct Mesh {
  std::vector<Triangle> tris;
  std::vector<uint32_t> first, corners;

  void index(size_t points) {
    first.assign(points + 1, 0);
    for (const Triangle& t : tris)
      for (uint32_t v : t) ++first[v + 1];
    for (size_t v = 0; v < points; ++v) first[v + 1] += first[v];
    corners.resize(tris.size() * 3);
    std::vector<uint32_t> at(first.begin(), first.end() - 1);
    for (uint32_t t = 0; t < tris.size(); ++t)
      for (uint32_t j = 0; j < 3; ++j) corners[at[tris[t][j]]++] = 3 * t + j;
  }
  uint32_t degree(uint32_t v) const { return first[v + 1] - first[v]; }
  uint32_t head(uint32_t c) const { return tris[c / 3][(c % 3 + 1) % 3]; }
  uint32_t tail(uint32_t c) const { return tris[c / 3][(c % 3 + 2) % 3]; }
  // The corner at a of the triangle holding the directed edge a -> b, or kNone.
  uint32_t edge(uint32_t a, uint32_t b) const {
    for (uint32_t i = first[a]; i < first[a + 1]; ++i)
      if (head(corners[i]) == b) return corners[i];
    return kNone;
  }
};

struct Checker {
  Geometry g;
  size_t points;
  std::vector<uint32_t>& off;

  // Steps that need a fresh index: each directed edge once, the boundary one simple cycle from the
  // lexicographically smallest vertex (into `cycle`, `next`: the boundary edge out of each vertex).
  bool boundary(const Mesh& m, std::vector<uint32_t>& cycle, std::vector<uint32_t>& next) {
    next.assign(points, kNone);
    std::vector<uint32_t> in(points, 0), heads;
    uint32_t lowest = kNone;
    for (uint32_t v = 0; v < points; ++v) {
      if (!m.degree(v)) continue;
      if (lowest == kNone || g.less(v, lowest)) lowest = v;
      heads.clear();
      for (uint32_t i = m.first[v]; i < m.first[v + 1]; ++i) heads.push_back(m.head(m.corners[i]));
      std::sort(heads.begin(), heads.end());
      for (size_t i = 1; i < heads.size(); ++i)
        if (heads[i] == heads[i - 1]) off.insert(off.end(), {v, heads[i]});
    }
    if (!off.empty()) return false;
    for (uint32_t c = 0; c < m.corners.size(); ++c) {
      const uint32_t a = m.tris[c / 3][c % 3], b = m.head(c);
      if (m.edge(b, a) != kNone) continue;
      if (next[a] != kNone) off.push_back(a);
      next[a] = b;
      ++in[b];
    }
    for (uint32_t v = 0; v < points; ++v)
      if (in[v] > 1 || (in[v] == 1) != (next[v] != kNone)) off.push_back(v);
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
    for (uint32_t v = 0; v < points; ++v)  // holes and other pieces
      if (next[v] != kNone && !seen[v]) off.push_back(v);
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
  void fans(const Mesh& m, const std::vector<uint32_t>& next) {
    for (uint32_t v = 0; v < points; ++v) {
      const uint32_t degree = m.degree(v);
      if (!degree) continue;
      const bool on_boundary = next[v] != kNone;
      const uint32_t c0 = on_boundary ? m.edge(v, next[v]) : m.corners[m.first[v]];
      uint32_t c = c0, count = 0, crossings = 0, last = m.head(c0);
      bool closed = false;
      while (count <= degree) {
        ++count;
        const uint32_t b = m.tail(c);  // the triangle (v, last, b) turns from last to b
        crossings += !g.upper(v, last) && g.upper(v, b);
        last = b;
        const uint32_t nc = m.edge(v, b);
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
      if (!ok) off.push_back(v);
    }
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

void normalise(std::vector<Triangle>& tris) {
  for (Triangle& t : tris) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(tris.begin(), tris.end());
  tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
}

StartSlots slots_of(const Mesh& m, const std::vector<uint32_t>& cycle, size_t points) {
  const uint32_t f = uint32_t(m.tris.size()), h = uint32_t(cycle.size());
  StartSlots s;
  s.finite = f;
  s.verts.resize(3 * size_t(f + h));
  s.nbrs.resize(3 * size_t(f + h));
  std::vector<uint32_t> pos(points, kNone);
  for (uint32_t i = 0; i < h; ++i) pos[cycle[i]] = i;
  for (uint32_t v = 0; v < points; ++v) s.vertices += m.degree(v) > 0;
  for (uint32_t t = 0; t < f; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      s.verts[3 * t + k] = m.tris[t][k];
      const uint32_t a = m.tris[t][(k + 1) % 3], b = m.tris[t][(k + 2) % 3], c = m.edge(b, a);
      if (c != kNone) {
        s.nbrs[3 * t + k] = NBR(c / 3, (c % 3 + 2) % 3);
        continue;
      }
      const uint32_t inf = f + pos[a];  // (b, a, INF): its edge 2 is b -> a
      s.nbrs[3 * t + k] = NBR(inf, 2u);
      s.nbrs[3 * size_t(inf) + 2] = NBR(t, k);
    }
  for (uint32_t i = 0; i < h; ++i) {
    const uint32_t inf = f + i;
    s.verts[3 * size_t(inf)] = cycle[(i + 1) % h];
    s.verts[3 * size_t(inf) + 1] = cycle[i];
    s.verts[3 * size_t(inf) + 2] = INF_VERTEX;
    s.nbrs[3 * size_t(inf)] = NBR(f + (i + h - 1) % h, 1u);  // a -> INF meets INF -> a of the edge before
    s.nbrs[3 * size_t(inf) + 1] = NBR(f + (i + 1) % h, 0u);
  }
  return s;
}

}  // namespace

std::optional<StartSlots> dual_to_slots(std::span<const double> xy, std::vector<Triangle> tris,
                                        std::vector<uint32_t>& offenders) {
  const size_t points = xy.size() / 2;
  offenders.clear();
  Checker ck{Geometry{xy}, points, offenders};
  auto fail = [&]() -> std::optional<StartSlots> {
    std::sort(offenders.begin(), offenders.end());
    offenders.erase(std::unique(offenders.begin(), offenders.end()), offenders.end());
    return std::nullopt;
  };
  normalise(tris);
  for (const Triangle& t : tris)
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || ck.g.orient(t[0], t[1], t[2]) <= 0)
      offenders.insert(offenders.end(), t.begin(), t.end());
  if (!offenders.empty() || tris.empty()) return fail();
  Mesh m;
  m.tris = std::move(tris);
  m.index(points);
  std::vector<uint32_t> cycle, next;
  if (!ck.boundary(m, cycle, next)) return fail();
  if (ck.fill(m, cycle)) {  // fill triangles are counter-clockwise by construction (a reflex turn reversed)
    normalise(m.tris);
    m.index(points);
    if (!ck.boundary(m, cycle, next)) return fail();
  }
  ck.fans(m, next);
  ck.convex(cycle);
  if (!offenders.empty()) return fail();
  uint64_t vertices = 0;
  for (uint32_t v = 0; v < points; ++v) vertices += m.degree(v) > 0;
  const uint64_t f = m.tris.size(), edges = (3 * f + cycle.size()) / 2;
  if (vertices + f != edges + 1) return fail();  // Euler: a disc (no repair known)
  return slots_of(m, cycle, points);
}

}  // namespace cdtgpu::gpu
