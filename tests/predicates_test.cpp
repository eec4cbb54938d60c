// core/predicates against CGAL (Epick's exact-sign orientation and side_of_oriented_circle, and
// Delaunay_triangulation_2::side_of_oriented_circle(..., perturb=true)) on generated cases: random points,
// near-degenerate ones (collinear / co-circular points moved by a few ulps), integer grids and lattice circles
// (exact zeros), UTM-like coordinates with millimetre detail, tiny and huge extents. Every case must agree.
#include <gtest/gtest.h>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/predicates.hpp"

namespace {

using cdtgpu::pred::XY;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P = K::Point_2;

struct Rng {
  explicit Rng(uint64_t seed) : g(seed) {}
  double unit() { return static_cast<double>(g() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int64_t integer(int64_t lo, int64_t hi) { return lo + static_cast<int64_t>(g() % uint64_t(hi - lo + 1)); }
  std::mt19937_64 g;
};

// v moved by k ulps (k may be negative).
double nudge(double v, int k) {
  for (; k > 0; --k) v = std::nextafter(v, HUGE_VAL);
  for (; k < 0; ++k) v = std::nextafter(v, -HUGE_VAL);
  return v;
}

XY nudge(Rng& r, XY p) {
  int k = static_cast<int>(r.integer(-2, 2));
  if (r.g() & 1) return {nudge(p.x, k), p.y};
  return {p.x, nudge(p.y, k)};
}

P cg(XY p) { return P(p.x, p.y); }

// Lattice points on circles of radius 5, 25, 65 and 1105 about the origin (many integer points each).
std::vector<std::vector<XY>> lattice_circles() {
  std::vector<std::vector<XY>> out;
  for (int64_t r : {5, 25, 65, 1105}) {
    std::vector<XY> pts;
    for (int64_t x = -r; x <= r; ++x) {
      int64_t y2 = r * r - x * x;
      auto y = static_cast<int64_t>(std::llround(std::sqrt(static_cast<double>(y2))));
      if (y * y != y2) continue;
      pts.push_back({double(x), double(y)});
      if (y) pts.push_back({double(x), double(-y)});
    }
    out.push_back(pts);
  }
  return out;
}

// Four distinct points of one lattice circle (or the corners of a grid rectangle), moved by an exactly
// representable offset and scaled by a power of two, so they stay exactly co-circular.
std::array<XY, 4> cocircular(Rng& r, const std::vector<std::vector<XY>>& circles, double scale, XY offset) {
  std::array<XY, 4> q;
  if (r.g() % 4 == 0) {
    double x0 = double(r.integer(-50, 50)), y0 = double(r.integer(-50, 50));
    double w = double(r.integer(1, 3)), h = double(r.integer(1, 3));
    q = {XY{x0, y0}, XY{x0 + w, y0}, XY{x0 + w, y0 + h}, XY{x0, y0 + h}};
    std::shuffle(q.begin(), q.end(), r.g);
  } else {
    const auto& c = circles[r.g() % circles.size()];
    size_t idx[4];
    for (int i = 0; i < 4; ++i) {
      bool again;
      do {
        idx[i] = r.g() % c.size();
        again = false;
        for (int j = 0; j < i; ++j) again |= idx[j] == idx[i];
      } while (again);
      q[i] = c[idx[i]];
    }
  }
  for (auto& p : q) p = {offset.x + p.x * scale, offset.y + p.y * scale};
  return q;
}

// A named family of cases: fills pts (3 or 4 points) from the generator.
struct Family {
  std::string name;
  int64_t count;
  std::function<void(Rng&, XY*)> gen;
  bool expect_zeros = false;
};

// Runs every family, comparing `ours` with `ref` case by case.
template <class Ours, class Ref>
void run_families(const std::vector<Family>& fams, Ours ours, Ref ref, int64_t min_total) {
  int64_t total = 0;
  uint64_t seed = 1;
  for (const auto& f : fams) {
    Rng r(seed++);
    int64_t bad = 0, zeros = 0;
    XY p[4];
    for (int64_t i = 0; i < f.count; ++i) {
      f.gen(r, p);
      int a = ours(p), b = ref(p);
      zeros += a == 0;
      if (a != b && ++bad <= 5) {
        ADD_FAILURE() << f.name << " case " << i << ": ours " << a << " CGAL " << b << " points "
                      << std::hexfloat << p[0].x << ',' << p[0].y << ' ' << p[1].x << ',' << p[1].y << ' '
                      << p[2].x << ',' << p[2].y << ' ' << p[3].x << ',' << p[3].y << std::defaultfloat;
      }
    }
    EXPECT_EQ(bad, 0) << f.name;
    std::printf("%-20s %9lld cases, %9lld zero signs\n", f.name.c_str(), (long long)f.count, (long long)zeros);
    // Families built to be degenerate must really produce exact zeros, or they test nothing special.
    if (f.expect_zeros) {
      EXPECT_GT(zeros, f.count / 50) << f.name;
    }
    total += f.count;
  }
  EXPECT_GE(total, min_total);
}

int orient_cgal(const XY* p) {
  return static_cast<int>(CGAL::orientation(cg(p[0]), cg(p[1]), cg(p[2])));
}
int incircle_cgal(const XY* p) {
  return static_cast<int>(CGAL::side_of_oriented_circle(cg(p[0]), cg(p[1]), cg(p[2]), cg(p[3])));
}

// Three points near a line through random a, b in the box [lo, hi]^2: c is rounded onto it and then moved
// by up to two ulps; the points are returned in a random order.
void near_line(Rng& r, XY* p, double lo, double hi) {
  XY a{r.uniform(lo, hi), r.uniform(lo, hi)}, b{r.uniform(lo, hi), r.uniform(lo, hi)};
  double t = r.uniform(-1, 2);
  XY c = nudge(r, {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
  XY q[3] = {a, b, c};
  std::shuffle(q, q + 3, r.g);
  p[0] = q[0], p[1] = q[1], p[2] = q[2];
}

// Four points near a circle of centre (cx, cy) and radius rad, the last moved by up to two ulps.
void near_circle(Rng& r, XY* p, double cx, double cy, double rad) {
  for (int i = 0; i < 4; ++i) {
    double t = r.uniform(0, 6.283185307179586);
    p[i] = {cx + rad * std::cos(t), cy + rad * std::sin(t)};
  }
  p[3] = nudge(r, p[3]);
}

double mm(Rng& r, double lo, double hi) { return std::round(r.uniform(lo, hi) * 1000.0) / 1000.0; }

std::vector<Family> orient_families() {
  return {
      {"random_1e9", 2'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 3; ++i) p[i] = {r.uniform(-1e9, 1e9), r.uniform(-1e9, 1e9)};
       }},
      {"near_line_unit", 1'500'000, [](Rng& r, XY* p) { near_line(r, p, -1, 1); }},
      {"near_line_1e9", 1'000'000, [](Rng& r, XY* p) { near_line(r, p, -1e9, 1e9); }},
      {"int_grid", 2'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 3; ++i) p[i] = {double(r.integer(-6, 6)), double(r.integer(-6, 6))};
       }, true},
      {"exact_line", 500'000,
       [](Rng& r, XY* p) {  // exactly collinear: a + k (dx, dy), all integers times 2^-10 around 6e6
         double ax = 500000 + r.integer(-1000, 1000) / 1024.0, ay = 6000000 + r.integer(-1000, 1000) / 1024.0;
         double dx = r.integer(-50, 50) / 1024.0, dy = r.integer(-50, 50) / 1024.0;
         for (int i = 0; i < 3; ++i) {
           double k = double(r.integer(-20, 20));
           p[i] = {ax + k * dx, ay + k * dy};
         }
       }, true},
      {"utm_mm", 1'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 3; ++i) p[i] = {mm(r, 4.9e5, 5.1e5), mm(r, 5.99e6, 6.01e6)};
       }},
      {"utm_mm_near_line", 1'000'000,
       [](Rng& r, XY* p) {
         near_line(r, p, 0, 1);
         for (int i = 0; i < 3; ++i) p[i] = {500000.0 + p[i].x * 100, 6000000.0 + p[i].y * 100};
         p[2] = nudge(r, p[2]);
       }},
      {"tiny_1e-50", 500'000, [](Rng& r, XY* p) { near_line(r, p, 1e-50, 2e-50); }},
      {"huge_1e60", 500'000, [](Rng& r, XY* p) { near_line(r, p, -1e60, 1e60); }},
  };
}

std::vector<Family> incircle_families(const std::vector<std::vector<XY>>& circles) {
  return {
      {"random_1e9", 2'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 4; ++i) p[i] = {r.uniform(-1e9, 1e9), r.uniform(-1e9, 1e9)};
       }},
      {"near_circle_unit", 1'500'000, [](Rng& r, XY* p) { near_circle(r, p, 0.3, -0.2, 1.0); }},
      {"near_circle_utm", 1'000'000, [](Rng& r, XY* p) { near_circle(r, p, 500000.0, 6000000.0, 3.0); }},
      {"int_grid", 2'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 4; ++i) p[i] = {double(r.integer(-4, 4)), double(r.integer(-4, 4))};
       }, true},
      {"lattice_circle", 1'000'000,
       [&circles](Rng& r, XY* p) {
         auto q = cocircular(r, circles, 1.0 / 1024.0, {500000.0, 6000000.0});
         for (int i = 0; i < 4; ++i) p[i] = q[i];
       }, true},
      {"lattice_circle_ulp", 500'000,
       [&circles](Rng& r, XY* p) {
         auto q = cocircular(r, circles, 0.25, {1000.0, -2000.0});
         for (int i = 0; i < 4; ++i) p[i] = q[i];
         p[r.g() % 4] = nudge(r, p[r.g() % 4]);
       }},
      {"utm_mm", 1'000'000,
       [](Rng& r, XY* p) {
         for (int i = 0; i < 4; ++i) p[i] = {mm(r, 499990, 500010), mm(r, 5999990, 6000010)};
       }},
      {"tiny_1e-50", 500'000, [](Rng& r, XY* p) { near_circle(r, p, 3e-50, 1e-50, 1e-50); }},
      {"huge_1e60", 500'000, [](Rng& r, XY* p) { near_circle(r, p, 1e60, -2e60, 1e59); }},
  };
}

TEST(Predicates, Orient2dMatchesCgal) {
  run_families(
      orient_families(), [](const XY* p) { return cdtgpu::pred::orient2d(p[0], p[1], p[2]); }, orient_cgal,
      10'000'000);
}

TEST(Predicates, IncircleMatchesCgal) {
  auto circles = lattice_circles();
  run_families(
      incircle_families(circles),
      [](const XY* p) { return cdtgpu::pred::incircle(p[0], p[1], p[2], p[3]); }, incircle_cgal,
      10'000'000);
}

// The exact stages alone, so that they are checked on inputs the filter would have decided.
TEST(Predicates, ExactStagesMatchCgal) {
  auto circles = lattice_circles();
  std::vector<Family> o = orient_families(), c = incircle_families(circles);
  for (auto& f : o) f.count /= 20;
  for (auto& f : c) f.count /= 20;
  run_families(
      o, [](const XY* p) { return cdtgpu::pred::orient2d_exact(p[0], p[1], p[2]); }, orient_cgal, 500'000);
  run_families(
      c, [](const XY* p) { return cdtgpu::pred::incircle_exact(p[0], p[1], p[2], p[3]); }, incircle_cgal,
      500'000);
}

TEST(Predicates, PerturbedIncircleMatchesCgalDelaunay) {
  auto circles = lattice_circles();
  CGAL::Delaunay_triangulation_2<K> dt;
  auto ref = [&dt](const XY* p) {
    P q[4] = {cg(p[0]), cg(p[1]), cg(p[2]), cg(p[3])};
    return static_cast<int>(dt.side_of_oriented_circle(q[0], q[1], q[2], q[3], true));
  };
  auto ours = [](const XY* p) { return cdtgpu::pred::incircle_perturbed(p[0], p[1], p[2], p[3]); };
  auto lattice = [&circles](double scale, XY offset) {
    return [&circles, scale, offset](Rng& r, XY* p) {
      auto q = cocircular(r, circles, scale, offset);
      for (int i = 0; i < 4; ++i) p[i] = q[i];
    };
  };
  // Triangles taken counter-clockwise, as a triangulation hands them over, and also as drawn.
  auto ccw = [](auto gen) {
    return [gen](Rng& r, XY* p) {
      gen(r, p);
      if (cdtgpu::pred::orient2d(p[0], p[1], p[2]) < 0) std::swap(p[0], p[1]);
    };
  };
  std::vector<Family> fams = {
      {"lattice_ccw", 3'000'000, ccw(lattice(1.0, {0, 0}))},
      {"lattice_any", 2'000'000, lattice(1.0, {0, 0})},
      {"lattice_utm_ccw", 2'000'000, ccw(lattice(1.0 / 1024.0, {500000.0, 6000000.0}))},
      {"lattice_tiny_ccw", 500'000, ccw(lattice(0x1.0p-170, {0, 0}))},
      {"lattice_huge_ccw", 500'000, ccw(lattice(0x1.0p200, {0x1.0p210, -0x1.0p211}))},
      {"int_grid", 2'000'000,  // repeated and collinear points too: the rule must match CGAL's code as is
       [](Rng& r, XY* p) {
         for (int i = 0; i < 4; ++i) p[i] = {double(r.integer(-2, 2)), double(r.integer(-2, 2))};
       }},
  };
  run_families(fams, ours, ref, 10'000'000);
}

// Hand-checked signs pin the convention independently of CGAL.
TEST(Predicates, SignConventions) {
  using namespace cdtgpu::pred;
  EXPECT_EQ(orient2d({0, 0}, {1, 0}, {0, 1}), 1);
  EXPECT_EQ(orient2d({0, 0}, {0, 1}, {1, 0}), -1);
  EXPECT_EQ(orient2d({0, 0}, {1, 1}, {3, 3}), 0);
  EXPECT_EQ(incircle({0, 0}, {1, 0}, {0, 1}, {0.5, 0.5}), 1);
  EXPECT_EQ(incircle({0, 0}, {1, 0}, {0, 1}, {2, 2}), -1);
  EXPECT_EQ(incircle({0, 0}, {1, 0}, {0, 1}, {1, 1}), 0);
  EXPECT_EQ(incircle({0, 0}, {0, 1}, {1, 0}, {0.5, 0.5}), -1);
  // Unit square, CCW triangle (0,0),(1,0),(1,1), query (0,1): the largest point (1,1) is p2 and
  // orient2d(p0, p1, p) = orient((0,0),(1,0),(0,1)) = +1, so the perturbed answer is "inside".
  EXPECT_EQ(incircle_perturbed({0, 0}, {1, 0}, {1, 1}, {0, 1}), 1);
  // Query (1,1) is the largest point itself: "outside".
  EXPECT_EQ(incircle_perturbed({0, 0}, {1, 0}, {0, 1}, {1, 1}), -1);
  // One ulp off the line decides without any perturbation.
  EXPECT_EQ(orient2d({0, 0}, {1, 1}, {3, std::nextafter(3.0, 4.0)}), 1);
}

}  // namespace
