// Marching triangles, then chaining (rules in contours.hpp). Triangles are bucketed by the levels they cross
// (a CSR list, each level's triangles in mesh order); levels are independent and run in parallel. Chaining
// goes through edge keys (the two vertex indices), never through coordinates, so equal-looking points never
// join lines that do not meet. Cost: O(triangles + segments), the chaining through a hash map per level.
#include "core/contours.hpp"

#include <algorithm>
#include <cmath>
#include <execution>
#include <numeric>
#include <span>
#include <string>
#include <unordered_map>

#include "core/error.hpp"

namespace cdtgpu {

namespace {

Point3 crossing(const Point3& u, const Point3& v, double level) {  // u below, v above
  if (v.z == level) return {v.x, v.y, level};
  const double t = (level - u.z) / (v.z - u.z);
  return {u.x + t * (v.x - u.x), u.y + t * (v.y - u.y), level};
}

// `tris`: the triangles, in mesh order, with a vertex below the level and one at or above it.
std::vector<Contour> lines_at(const Mesh& mesh, double level, std::span<const uint32_t> tris) {
  std::vector<ContourSegment> segs;
  for (uint32_t t : tris) {
    const Triangle& tri = mesh.triangles[t];
    const Point3* p[3] = {&mesh.vertices[tri[0]], &mesh.vertices[tri[1]], &mesh.vertices[tri[2]]};
    const bool above[3] = {p[0]->z >= level, p[1]->z >= level, p[2]->z >= level};
    if (above[0] == above[1] && above[1] == above[2]) continue;
    // Walking the triangle counter-clockwise, the edge going from above to below ("falling") and the one
    // going from below to above ("rising"); falling -> rising keeps the above corner on the left.
    int falling = -1, rising = -1;
    for (int e = 0; e < 3; ++e) {
      const int f = (e + 1) % 3;
      if (above[e] && !above[f]) falling = e;
      if (!above[e] && above[f]) rising = e;
    }
    const auto point = [&](int e) {
      const int f = (e + 1) % 3;
      return above[e] ? crossing(*p[f], *p[e], level) : crossing(*p[e], *p[f], level);
    };
    const auto key = [&](int e) { return contour_edge_key(tri[e], tri[(e + 1) % 3]); };
    ContourSegment s{key(falling), key(rising), point(falling), point(rising)};
    // A clockwise triangle (never in a canonical mesh) walks the other way round.
    const Point3 &a = *p[0], &b = *p[1], &c = *p[2];
    if ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) < 0) {
      std::swap(s.from, s.to);
      std::swap(s.p, s.q);
    }
    segs.push_back(s);
  }
  return chain_contours(level, segs);
}

}  // namespace

uint64_t contour_edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a;
}

std::vector<Contour> chain_contours(double level, const std::vector<ContourSegment>& segs) {
  std::unordered_map<uint64_t, uint32_t> starting, ending;  // edge key -> segment
  starting.reserve(segs.size());
  ending.reserve(segs.size());
  for (uint32_t i = 0; i < segs.size(); ++i) {
    starting.emplace(segs[i].from, i);
    ending.emplace(segs[i].to, i);
  }
  std::vector<bool> used(segs.size(), false);
  std::vector<Contour> out;
  const auto chain = [&](uint32_t first, bool closed) {
    Contour c;
    c.level = level;
    c.closed = closed;
    c.points.push_back(segs[first].p);
    for (uint32_t i = first;;) {
      used[i] = true;
      c.points.push_back(segs[i].q);
      auto next = starting.find(segs[i].to);
      if (next == starting.end() || used[next->second]) break;
      i = next->second;
    }
    c.points.erase(std::unique(c.points.begin(), c.points.end()), c.points.end());
    const size_t distinct = c.points.size() - (closed ? 1 : 0);
    if (distinct >= 2) out.push_back(std::move(c));
  };
  // Open lines start where no segment ends (the mesh boundary; or, in a mesh that is not a manifold, where
  // two segments start); what is left are rings.
  for (uint32_t i = 0; i < segs.size(); ++i)
    if (!used[i] && (!ending.contains(segs[i].from) || starting.at(segs[i].from) != i)) chain(i, false);
  for (uint32_t i = 0; i < segs.size(); ++i)
    if (!used[i]) chain(i, true);
  return out;
}

namespace {

int64_t first_level_above(double z, double interval) {  // smallest k with k * interval > z
  auto k = int64_t(std::floor(z / interval)) + 1;
  while (double(k - 1) * interval > z) --k;
  while (double(k) * interval <= z) ++k;
  return k;
}

int64_t last_level_at_or_below(double z, double interval) {  // largest k with k * interval <= z
  auto k = int64_t(std::floor(z / interval));
  while (double(k) * interval > z) --k;
  while (double(k + 1) * interval <= z) ++k;
  return k;
}

}  // namespace

ContourLevels contour_levels(const Mesh& mesh, double interval, uint64_t max_levels) {
  if (!(interval > 0) || !std::isfinite(interval))
    throw UsageError("the contour interval must be a positive number, not " + number_text(interval));
  ContourLevels out;
  out.interval = interval;
  if (mesh.triangles.empty()) return out;
  double z0 = INFINITY, z1 = -INFINITY;
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t) {
      z0 = std::min(z0, mesh.vertices.at(v).z);
      z1 = std::max(z1, mesh.vertices.at(v).z);
    }
  if (std::fabs(z0 / interval) > 9e15 || std::fabs(z1 / interval) > 9e15 ||
      (z1 - z0) / interval > double(max_levels))
    throw UsageError("contour interval " + number_text(interval) + " gives more than " +
                     std::to_string(max_levels) + " levels between " + number_text(z0) + " and " +
                     number_text(z1) + ": choose a larger --interval");
  // Level k is at k * interval; a triangle crosses it when its lowest z < level <= its highest z.
  const int64_t k0 = first_level_above(z0, interval), k1 = last_level_at_or_below(z1, interval);
  if (k1 >= k0) out.k0 = k0, out.count = size_t(k1 - k0 + 1);
  return out;
}

std::vector<Contour> contour_lines(const Mesh& mesh, double interval, uint64_t max_levels) {
  const ContourLevels lv = contour_levels(mesh, interval, max_levels);
  if (lv.count == 0) return {};
  const int64_t k0 = lv.k0;
  const size_t levels = lv.count;
  auto first_above = [&](double z) { return first_level_above(z, interval); };
  auto last_at_or_below = [&](double z) { return last_level_at_or_below(z, interval); };
  // The triangles of each level, in mesh order (a CSR list).
  const size_t nt = mesh.triangles.size();
  std::vector<std::pair<int64_t, int64_t>> range(nt);
  std::vector<uint64_t> start(levels + 1, 0);
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& tri = mesh.triangles[t];
    const double lo = std::min({mesh.vertices[tri[0]].z, mesh.vertices[tri[1]].z, mesh.vertices[tri[2]].z});
    const double hi = std::max({mesh.vertices[tri[0]].z, mesh.vertices[tri[1]].z, mesh.vertices[tri[2]].z});
    range[t] = {first_above(lo) - k0, last_at_or_below(hi) - k0};
    for (int64_t k = range[t].first; k <= range[t].second; ++k) ++start[size_t(k) + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<uint32_t> list(start.back());
  {
    std::vector<uint64_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < nt; ++t)
      for (int64_t k = range[t].first; k <= range[t].second; ++k) list[fill[size_t(k)]++] = uint32_t(t);
  }
  std::vector<size_t> ks(levels);
  std::iota(ks.begin(), ks.end(), size_t(0));
  std::vector<std::vector<Contour>> per(levels);
  std::transform(std::execution::par, ks.begin(), ks.end(), per.begin(), [&](size_t k) {
    const std::span<const uint32_t> tris(list.data() + start[k], start[k + 1] - start[k]);
    return lines_at(mesh, lv.level(k), tris);
  });
  std::vector<Contour> all;
  for (auto& v : per)
    for (Contour& c : v) all.push_back(std::move(c));
  return all;
}

}  // namespace cdtgpu
