// apply_z_rules: constants, draping and flattening. Cost: one CDT of the inputs with z (when anything is
// draped), a uniform grid of its triangles' bounding boxes (about one triangle per cell), then per draped
// vertex the triangles of one cell tested with exact orientation.
#include "core/drape.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P2 = K::Point_2;

P2 p2(const Point3& p) { return {p.x, p.y}; }

}  // namespace

DrapeSurface::DrapeSurface(Mesh surface) : mesh_(std::move(surface)) {
  const Points& vs = mesh_.vertices;
  const Triangles& ts = mesh_.triangles;
  if (ts.empty()) throw std::invalid_argument("DrapeSurface: no triangles");
  double x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  x0_ = y0_ = HUGE_VAL;
  for (const Point3& p : vs) {
    x0_ = std::min(x0_, p.x), y0_ = std::min(y0_, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  const double w = std::max(x1 - x0_, 1e-300), h = std::max(y1 - y0_, 1e-300);
  const double cells = std::max<double>(1, double(ts.size()));
  nx_ = uint32_t(std::clamp(std::sqrt(cells * w / h), 1.0, 4096.0));
  ny_ = uint32_t(std::clamp(cells / nx_, 1.0, 4096.0));
  cell_w_ = w / nx_;
  cell_h_ = h / ny_;
  first_.assign(size_t(nx_) * ny_ + 1, 0);
  auto for_cells = [&](const Triangle& t, auto&& f) {
    const Point3 &a = vs[t[0]], &b = vs[t[1]], &c = vs[t[2]];
    const uint32_t cx0 = cell_x(std::min({a.x, b.x, c.x})), cx1 = cell_x(std::max({a.x, b.x, c.x}));
    const uint32_t cy0 = cell_y(std::min({a.y, b.y, c.y})), cy1 = cell_y(std::max({a.y, b.y, c.y}));
    for (uint32_t j = cy0; j <= cy1; ++j)
      for (uint32_t i = cx0; i <= cx1; ++i) f(size_t(j) * nx_ + i);
  };
  for (const Triangle& t : ts) for_cells(t, [&](size_t c) { ++first_[c + 1]; });
  for (size_t c = 0; c + 1 < first_.size(); ++c) first_[c + 1] += first_[c];
  cells_.resize(first_.back());
  std::vector<uint32_t> cursor(first_.begin(), first_.end() - 1);
  for (uint32_t t = 0; t < ts.size(); ++t) for_cells(ts[t], [&](size_t c) { cells_[cursor[c]++] = t; });

  // Hull edges: the directed edges whose reverse is in no triangle.
  std::vector<uint64_t> keys;
  keys.reserve(ts.size() * 3);
  for (const Triangle& t : ts)
    for (int k = 0; k < 3; ++k) keys.push_back(uint64_t(t[k]) << 32 | t[(k + 1) % 3]);
  std::sort(keys.begin(), keys.end());
  for (uint64_t k : keys) {
    const uint32_t a = uint32_t(k >> 32), b = uint32_t(k);
    if (!std::binary_search(keys.begin(), keys.end(), uint64_t(b) << 32 | a)) hull_.push_back({a, b});
  }
}

uint32_t DrapeSurface::cell_x(double x) const {
  return uint32_t(std::clamp(std::floor((x - x0_) / cell_w_), 0.0, double(nx_ - 1)));
}
uint32_t DrapeSurface::cell_y(double y) const {
  return uint32_t(std::clamp(std::floor((y - y0_) / cell_h_), 0.0, double(ny_ - 1)));
}

double DrapeSurface::z_at(double x, double y, bool* outside) const {
  const Points& vs = mesh_.vertices;
  const P2 p(x, y);
  const size_t cell = size_t(cell_y(y)) * nx_ + cell_x(x);
  uint32_t found = std::numeric_limits<uint32_t>::max();
  for (uint32_t i = first_[cell]; i < first_[cell + 1]; ++i) {
    const uint32_t t = cells_[i];
    if (t >= found) continue;
    const Triangle& tr = mesh_.triangles[t];
    const P2 a = p2(vs[tr[0]]), b = p2(vs[tr[1]]), c = p2(vs[tr[2]]);
    if (CGAL::orientation(a, b, p) != CGAL::RIGHT_TURN && CGAL::orientation(b, c, p) != CGAL::RIGHT_TURN &&
        CGAL::orientation(c, a, p) != CGAL::RIGHT_TURN)
      found = t;
  }
  if (outside) *outside = found == std::numeric_limits<uint32_t>::max();
  if (found != std::numeric_limits<uint32_t>::max()) {
    const Triangle& tr = mesh_.triangles[found];
    const Point3 &a = vs[tr[0]], &b = vs[tr[1]], &c = vs[tr[2]];
    const double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - a.x, vy = c.y - a.y, wx = x - a.x, wy = y - a.y;
    const double det = ux * vy - uy * vx;
    const double s = (wx * vy - wy * vx) / det, t = (ux * wy - uy * wx) / det;
    return a.z + s * (b.z - a.z) + t * (c.z - a.z);
  }
  // Beyond the hull: the nearest point of the nearest hull edge (the first such edge on ties).
  double best = HUGE_VAL, z = 0;
  for (const auto& [i, j] : hull_) {
    const Point3 &a = vs[i], &b = vs[j];
    const double ux = b.x - a.x, uy = b.y - a.y;
    const double t = std::clamp(((x - a.x) * ux + (y - a.y) * uy) / (ux * ux + uy * uy), 0.0, 1.0);
    const double dx = a.x + t * ux - x, dy = a.y + t * uy - y, d = dx * dx + dy * dy;
    if (d < best) best = d, z = a.z + t * (b.z - a.z);
  }
  return z;
}

DrapeStats apply_z_rules(InputSet& in, const std::vector<InputPart>& parts) {
  DrapeStats stats;
  bool any_draped = false;
  for (const InputPart& part : parts) {
    if (part.z.kind == ZRule::Kind::constant) {
      for (size_t i = part.points_begin; i < part.points_end; ++i) in.points[i].z = part.z.value;
      for (size_t i = part.lines_begin; i < part.lines_end; ++i)
        for (Point3& p : in.lines[i].points) p.z = part.z.value;
      stats.constant_vertices += part.points_end - part.points_begin;
      for (size_t i = part.lines_begin; i < part.lines_end; ++i)
        stats.constant_vertices += in.lines[i].points.size();
    }
    any_draped |= part.z.draped();
  }

  // Vertices read without z, in parts that keep z: 0, as before; not part of the surface. On all cores: every
  // run reads every vertex here (1.25B took 4.8 s on one).
  auto zero_missing = [&](const InputPart& part, uint64_t& count) {
    if (part.z.kind != ZRule::Kind::keep || part.z_complete) return;
    using Range = tbb::blocked_range<size_t>;
    count += tbb::parallel_reduce(Range(part.points_begin, part.points_end, 1 << 16), uint64_t(0),
                                  [&](const Range& r, uint64_t n) {
                                    for (size_t i = r.begin(); i < r.end(); ++i)
                                      if (is_missing_z(in.points[i].z)) in.points[i].z = 0, ++n;
                                    return n;
                                  }, std::plus<>());
    count += tbb::parallel_reduce(Range(part.lines_begin, part.lines_end), uint64_t(0),
                                  [&](const Range& r, uint64_t n) {
                                    for (size_t i = r.begin(); i < r.end(); ++i)
                                      for (Point3& p : in.lines[i].points)
                                        if (is_missing_z(p.z)) p.z = 0, ++n;
                                    return n;
                                  }, std::plus<>());
  };
  if (!any_draped) {
    for (const InputPart& part : parts) zero_missing(part, stats.zero_z.emplace_back(0));
    return stats;
  }

  InputSet known;
  for (const InputPart& part : parts) {
    if (part.z.kind != ZRule::Kind::keep) continue;
    for (size_t i = part.points_begin; i < part.points_end; ++i)
      if (!is_missing_z(in.points[i].z)) known.points.push_back(in.points[i]);
    for (size_t i = part.lines_begin; i < part.lines_end; ++i)
      if (std::none_of(in.lines[i].points.begin(), in.lines[i].points.end(),
                       [](const Point3& p) { return is_missing_z(p.z); }))
        known.lines.push_back(in.lines[i]);
  }
  for (const InputPart& part : parts) zero_missing(part, stats.zero_z.emplace_back(0));
  CdtResult surface = triangulate_cgal(prepare(known));
  if (surface.mesh.triangles.empty())
    throw UsageError("z=drape needs a surface: the vertices with their own z make " +
                     std::to_string(surface.mesh.vertices.size()) +
                     " distinct points, fewer than 3 or all on one line");
  const DrapeSurface drape(std::move(surface.mesh));

  auto drape_point = [&](Point3& p) {
    bool outside = false;
    p.z = drape.z_at(p.x, p.y, &outside);
    ++stats.draped_vertices;
    stats.outside_surface += outside;
  };
  for (const InputPart& part : parts) {
    if (!part.z.draped()) continue;
    for (size_t i = part.points_begin; i < part.points_end; ++i) drape_point(in.points[i]);
    for (size_t i = part.lines_begin; i < part.lines_end; ++i) {
      Points& pts = in.lines[i].points;
      for (Point3& p : pts) drape_point(p);
      if (pts.empty() || part.z.kind == ZRule::Kind::drape) continue;
      double lo = HUGE_VAL, hi = -HUGE_VAL, sum = 0;
      for (const Point3& p : pts) lo = std::min(lo, p.z), hi = std::max(hi, p.z), sum += p.z;
      const double flat = part.z.kind == ZRule::Kind::min   ? lo
                          : part.z.kind == ZRule::Kind::max ? hi
                                                            : sum / double(pts.size());
      for (Point3& p : pts) p.z = flat;
    }
  }
  return stats;
}

}  // namespace cdtgpu
