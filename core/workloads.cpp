// Deterministic synthetic inputs: uniform points, Delaunay-edge constraints, a Gaussian-hill DEM with contours.
// Cost: uniform O(n); constraints one CGAL Delaunay triangulation of f*n points plus a sort of its edges;
// terrain O(grid^2 * hills) plus marching squares O(lattice cells * levels).
#include "core/workloads.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;

// Each generator gets its own stream, so adding constraints does not replay the draws that placed the points.
constexpr uint64_t kConstraintStream = 0xD1B54A32D192ED03ULL;
constexpr uint64_t kTerrainStream = 0x9E3779B97F4A7C15ULL;

std::string fmt_double(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool less_xy(const Point3& a, const Point3& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
bool same_xy(const Point3& a, const Point3& b) { return a.x == b.x && a.y == b.y; }

// exp(-t) from +, *, / only, so every platform gets the same bits (libm's exp may differ in the last ulp):
// a degree-8 Taylor polynomial of exp(-t/1024) (error < 1e-18 for t <= 40) squared ten times. Relative error
// about 1e-13; values below exp(-40) are dropped, far under the millimetre the DEM is rounded to.
double exp_neg(double t) {
  if (t > 40) return 0;
  double s = t / 1024;
  double p = 1;
  for (int k = 8; k >= 1; --k) p = 1 - s * p / k;
  for (int k = 0; k < 10; ++k) p *= p;
  return p;
}

}  // namespace

double unit_double(uint64_t draw) { return static_cast<double>(draw >> 11) * 0x1.0p-53; }

double unit_double(std::mt19937_64& rng) { return unit_double(rng()); }

uint64_t uniform_below(std::mt19937_64& rng, uint64_t bound) {
  uint64_t threshold = (0 - bound) % bound;  // 2^64 mod bound
  for (;;) {
    uint64_t r = rng();
    if (r >= threshold) return r % bound;
  }
}

InputSet uniform_points(uint64_t n, uint64_t seed) {
  InputSet in;
  in.sources.push_back("uniform(n=" + std::to_string(n) + ",seed=" + std::to_string(seed) + ")");
  resize_unwritten(in.points, n);
  // The draws come from one stream, so they are made in order on one core, a block at a time; turning them
  // into points (and faulting the pages of 24 GB at 1B points) runs on all cores.
  constexpr uint64_t kBlock = uint64_t(1) << 20;
  std::vector<uint64_t> draws(3 * std::min(n, kBlock));
  std::mt19937_64 rng(seed);
  for (uint64_t first = 0; first < n; first += kBlock) {
    const uint64_t count = std::min(kBlock, n - first);
    for (uint64_t k = 0; k < 3 * count; ++k) draws[k] = rng();
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, count, 1 << 14), [&](const tbb::blocked_range<uint64_t>& r) {
      for (uint64_t i = r.begin(); i < r.end(); ++i) {
        const double ux = unit_double(draws[3 * i]), uy = unit_double(draws[3 * i + 1]),
                     uz = unit_double(draws[3 * i + 2]);
        // Integer millimetres divided once: the nearest double to the millimetre value.
        in.points[first + i] = Point3{(500000000.0 + std::floor(ux * 1e7)) / 1000,
                                      (6000000000.0 + std::floor(uy * 1e7)) / 1000, std::floor(uz * 1e5) / 1000};
      }
    });
  }
  return in;
}

void add_dt_edge_constraints(InputSet& in, uint64_t m, double f, uint64_t seed) {
  if (!(f > 0 && f <= 1)) throw UsageError("constraint subset fraction must be in (0, 1], got " + fmt_double(f));
  std::mt19937_64 rng(seed ^ kConstraintStream);
  const uint64_t n = in.points.size();
  uint64_t s = std::min<uint64_t>(n, static_cast<uint64_t>(std::llround(f * static_cast<double>(n))));

  // The subset: a partial Fisher-Yates shuffle of the indices.
  std::vector<uint32_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0u);
  for (uint64_t i = 0; i < s; ++i) std::swap(idx[i], idx[i + uniform_below(rng, n - i)]);
  Points sub(s);
  for (uint64_t i = 0; i < s; ++i) sub[i] = in.points[idx[i]];
  std::sort(sub.begin(), sub.end(), less_xy);
  sub.erase(std::unique(sub.begin(), sub.end(), same_xy), sub.end());

  std::vector<std::pair<K::Point_2, uint32_t>> pts(sub.size());
  for (size_t i = 0; i < sub.size(); ++i) pts[i] = {K::Point_2(sub[i].x, sub[i].y), static_cast<uint32_t>(i)};
  Delaunay dt;
  dt.insert(pts.begin(), pts.end());
  std::vector<Edge> edges;
  edges.reserve(3 * sub.size());
  for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
    uint32_t a = e->first->vertex(Delaunay::cw(e->second))->info();
    uint32_t b = e->first->vertex(Delaunay::ccw(e->second))->info();
    edges.push_back({std::min(a, b), std::max(a, b)});
  }
  std::sort(edges.begin(), edges.end());
  if (m > edges.size())
    throw UsageError(std::to_string(m) + " constraints asked for, but the Delaunay triangulation of " +
                     std::to_string(sub.size()) + " points (fraction " + fmt_double(f) + " of " +
                     std::to_string(n) + ") has only " + std::to_string(edges.size()) + " edges");

  uint32_t source = static_cast<uint32_t>(in.sources.size());
  in.sources.push_back("dt-edges(m=" + std::to_string(m) + ",f=" + fmt_double(f) + ",seed=" +
                       std::to_string(seed) + ")");
  in.lines.reserve(in.lines.size() + m);
  for (uint64_t i = 0; i < m; ++i) {
    std::swap(edges[i], edges[i + uniform_below(rng, edges.size() - i)]);
    Polyline line;
    line.points = {sub[edges[i][0]], sub[edges[i][1]]};
    line.source = source;
    line.record = i + 1;
    add_polyline(in, std::move(line));
  }
}

double Terrain::operator()(double x, double y) const {
  double h = 0;
  for (size_t k = 0; k < cx.size(); ++k) {
    double dx = x - cx[k], dy = y - cy[k];
    h += height[k] * exp_neg((dx * dx + dy * dy) / (2 * sigma[k] * sigma[k]));
  }
  return h;
}

Terrain make_terrain(const TerrainOptions& o) {
  std::mt19937_64 rng(o.seed ^ kTerrainStream);
  const double extent = o.spacing * (o.grid > 1 ? o.grid - 1 : 1);
  Terrain t;
  for (uint32_t k = 0; k < o.hills; ++k) {
    t.cx.push_back(unit_double(rng) * extent);
    t.cy.push_back(unit_double(rng) * extent);
    t.sigma.push_back(extent * (o.sigma_min + (o.sigma_max - o.sigma_min) * unit_double(rng)));
    t.height.push_back(40 + 160 * unit_double(rng));
  }
  return t;
}

namespace {

// Marching squares of one level over the lattice values v (A x B nodes, row-major): polylines as chains of
// lattice edge ids. Edge ids: 2*(b*A + a) is the edge from node (a,b) to (a+1,b), +1 the edge to (a,b+1).
struct ContourChains {
  std::vector<std::vector<uint32_t>> chains;
  std::vector<bool> closed;
};

ContourChains march_level(const std::vector<double>& v, uint32_t A, uint32_t B, double level) {
  auto above = [&](uint32_t a, uint32_t b) { return v[size_t(b) * A + a] >= level; };
  auto hid = [&](uint32_t a, uint32_t b) { return 2 * (b * A + a); };
  auto vid = [&](uint32_t a, uint32_t b) { return 2 * (b * A + a) + 1; };

  std::vector<std::array<uint32_t, 2>> segs;
  for (uint32_t b = 0; b + 1 < B; ++b)
    for (uint32_t a = 0; a + 1 < A; ++a) {
      bool c0 = above(a, b), c1 = above(a + 1, b), c2 = above(a + 1, b + 1), c3 = above(a, b + 1);
      uint32_t e0 = hid(a, b), e1 = vid(a + 1, b), e2 = hid(a, b + 1), e3 = vid(a, b);
      std::array<uint32_t, 4> cut{};
      int cuts = 0;
      if (c0 != c1) cut[cuts++] = e0;
      if (c1 != c2) cut[cuts++] = e1;
      if (c2 != c3) cut[cuts++] = e2;
      if (c3 != c0) cut[cuts++] = e3;
      if (cuts == 2) {
        segs.push_back({cut[0], cut[1]});
      } else if (cuts == 4) {
        // Saddle: if the centre is on c0's side, c0 and c2 connect through it and c1, c3 are cut off.
        double centre = (v[size_t(b) * A + a] + v[size_t(b) * A + a + 1] + v[size_t(b + 1) * A + a + 1] +
                         v[size_t(b + 1) * A + a]) / 4;
        if ((centre >= level) == c0) {
          segs.push_back({e0, e1});
          segs.push_back({e2, e3});
        } else {
          segs.push_back({e3, e0});
          segs.push_back({e1, e2});
        }
      }
    }

  // Each crossed lattice edge touches one segment per adjacent cell: at most two.
  std::unordered_map<uint32_t, std::array<int64_t, 2>> at;
  at.reserve(segs.size() * 2);
  for (size_t i = 0; i < segs.size(); ++i)
    for (uint32_t e : segs[i]) {
      auto [it, fresh] = at.try_emplace(e, std::array<int64_t, 2>{-1, -1});
      it->second[fresh ? 0 : 1] = static_cast<int64_t>(i);
    }
  auto other_seg = [&](uint32_t e, int64_t s) {
    const auto& p = at.at(e);
    return p[0] == s ? p[1] : p[0];
  };

  ContourChains out;
  std::vector<bool> used(segs.size(), false);
  auto walk = [&](size_t start, uint32_t from) {
    std::vector<uint32_t> chain{from};
    int64_t s = static_cast<int64_t>(start);
    uint32_t e = from;
    while (s >= 0 && !used[s]) {
      used[s] = true;
      e = segs[s][0] == e ? segs[s][1] : segs[s][0];
      chain.push_back(e);
      s = other_seg(e, s);
    }
    bool closed = chain.size() > 2 && chain.front() == chain.back();
    if (closed) chain.pop_back();
    out.chains.push_back(std::move(chain));
    out.closed.push_back(closed);
  };
  // Open contours first, from their ends on the lattice boundary, then the remaining loops.
  for (size_t i = 0; i < segs.size(); ++i)
    for (uint32_t e : segs[i])
      if (!used[i] && at.at(e)[1] < 0) walk(i, e);
  for (size_t i = 0; i < segs.size(); ++i)
    if (!used[i]) walk(i, segs[i][0]);
  return out;
}

}  // namespace

InputSet terrain_workload(const TerrainOptions& o) {
  if (o.grid < 2 || o.contour_step < 1 || !(o.spacing > 0))
    throw UsageError("terrain needs grid >= 2, contour_step >= 1 and spacing > 0");
  const Terrain terrain = make_terrain(o);
  const double x0 = kUniformX0, y0 = kUniformY0;
  InputSet in;
  std::string seed = std::to_string(o.seed);
  in.sources.push_back("terrain-dem(grid=" + std::to_string(o.grid) + ",seed=" + seed + ")");
  in.sources.push_back("terrain-contours(levels=" + std::to_string(o.levels) + ",seed=" + seed + ")");
  in.points.reserve(size_t(o.grid) * o.grid);
  for (uint32_t j = 0; j < o.grid; ++j)
    for (uint32_t i = 0; i < o.grid; ++i) {
      double x = i * o.spacing, y = j * o.spacing;
      add_point(in, 0, uint64_t(j) * o.grid + i + 1, {x0 + x, y0 + y, std::round(terrain(x, y) * 1000) / 1000});
    }

  // Lattice nodes at half a cell plus multiples of contour_step cells: their coordinates are never DEM node
  // coordinates, so a contour vertex (on a lattice edge) never coincides with a DEM point.
  const double step = o.spacing * o.contour_step;
  const double max_off = o.spacing * (o.grid - 1) - o.spacing / 2;
  const uint32_t A = max_off < 0 ? 0 : static_cast<uint32_t>(std::floor(max_off / step)) + 1;
  if (A < 2 || o.levels == 0) return in;
  std::vector<double> lx(A), v(size_t(A) * A);
  for (uint32_t a = 0; a < A; ++a) lx[a] = o.spacing / 2 + a * step;
  for (uint32_t b = 0; b < A; ++b)
    for (uint32_t a = 0; a < A; ++a) v[size_t(b) * A + a] = terrain(lx[a], lx[b]);
  auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  const double vmin = *lo, interval = (*hi - *lo) / o.levels;

  uint64_t record = 0;
  for (uint32_t k = 0; k < o.levels; ++k) {
    const double level = vmin + (k + 0.5) * interval;
    // The crossing on edge id e, interpolated from the edge's lower-index node, so both cells sharing the
    // edge (and the chain) see the same bits.
    auto vertex = [&](uint32_t e) {
      uint32_t node = e / 2, a = node % A, b = node / A;
      uint32_t a1 = a + (e % 2 == 0), b1 = b + (e % 2 == 1);
      double v0 = v[size_t(b) * A + a], v1 = v[size_t(b1) * A + a1];
      double t = (level - v0) / (v1 - v0);
      double x = lx[a] + t * (lx[a1] - lx[a]), y = lx[b] + t * (lx[b1] - lx[b]);
      return Point3{x0 + x, y0 + y, level};
    };
    ContourChains cc = march_level(v, A, A, level);
    for (size_t c = 0; c < cc.chains.size(); ++c) {
      Polyline line;
      line.closed = cc.closed[c];
      line.source = 1;
      line.record = ++record;
      for (uint32_t e : cc.chains[c]) line.points.push_back(vertex(e));
      add_polyline(in, std::move(line));
    }
  }
  return in;
}

uint64_t checksum(const InputSet& in) {
  uint64_t h = 0xcbf29ce484222325ULL;
  auto mix = [&](uint64_t w) {
    for (int i = 0; i < 8; ++i) {
      h ^= (w >> (8 * i)) & 0xff;
      h *= 0x100000001b3ULL;
    }
  };
  auto mix_point = [&](const Point3& p) {
    mix(std::bit_cast<uint64_t>(p.x));
    mix(std::bit_cast<uint64_t>(p.y));
    mix(std::bit_cast<uint64_t>(p.z));
  };
  mix(in.points.size());
  for (const Point3& p : in.points) mix_point(p);
  mix(in.lines.size());
  for (const Polyline& l : in.lines) {
    mix(l.points.size() * 2 + l.closed);
    for (const Point3& p : l.points) mix_point(p);
  }
  return h;
}

void add_band_chains(InputSet& in) {
  const size_t n = in.points.size();
  const double spacing = kUniformSide / std::sqrt(double(n));
  const auto band_of = [&](size_t i) { return uint64_t((in.points[i].y - kUniformY0) / spacing); };
  // Points of every fourth band, grouped by band (a counting sort), then each band sorted by (x, y, index) on
  // its own core: one std::sort of 250M (band, index) pairs through the points took minutes at 1B.
  const uint64_t chains = uint64_t(kUniformSide / spacing) / 4 + 1;  // bands 0, 4, 8, ... up to side / spacing
  std::vector<uint64_t> first(chains + 1, 0);
  for (size_t i = 0; i < n; ++i)
    if (const uint64_t b = band_of(i); b % 4 == 0 && b / 4 < chains) ++first[b / 4 + 1];
  for (uint64_t c = 0; c < chains; ++c) first[c + 1] += first[c];
  std::vector<uint32_t> members(first[chains]);
  std::vector<uint64_t> at(first.begin(), first.end() - 1);
  for (size_t i = 0; i < n; ++i)
    if (const uint64_t b = band_of(i); b % 4 == 0 && b / 4 < chains) members[at[b / 4]++] = uint32_t(i);
  std::vector<Polyline> lines(chains);
  tbb::parallel_for(uint64_t(0), chains, [&](uint64_t c) {
    const auto begin = members.begin() + first[c], end = members.begin() + first[c + 1];
    std::sort(begin, end, [&](uint32_t a, uint32_t b) {
      const Point3& p = in.points[a];
      const Point3& q = in.points[b];
      return p.x != q.x ? p.x < q.x : p.y != q.y ? p.y < q.y : a < b;
    });
    for (auto it = begin; it != end; ++it) lines[c].points.push_back(in.points[*it]);
  });
  for (Polyline& line : lines)
    if (line.points.size() >= 2) in.lines.push_back(std::move(line));
}


}  // namespace cdtgpu
