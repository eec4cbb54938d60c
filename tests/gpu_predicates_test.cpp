// shaders/predicates.glsl (run by shaders/predicates_eval.comp) against core/predicates on the CPU, and every
// 16th case also against CGAL: orient2d, incircle and the perturbed incircle must give the same sign on every
// case. The cases mix random points, near-collinear / near-co-circular points moved by ulps, integer grids and
// exactly co-circular lattice points (the exact stages), UTM-like millimetre coordinates, tiny and huge
// extents. 1M cases by default (lavapipe is slow); CDTGPU_LARGE=1 runs 10M.
#include <gtest/gtest.h>

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include "core/predicates.hpp"
#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/recorder.hpp"

namespace {

using cdtgpu::pred::XY;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;

struct Rng {
  explicit Rng(uint64_t seed) : g(seed) {}
  double unit() { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int64_t integer(int64_t lo, int64_t hi) { return lo + static_cast<int64_t>(g() % uint64_t(hi - lo + 1)); }
  std::mt19937_64 g;
};

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

// Integer points on circles of radius 5, 25, 65 and 1105 about the origin.
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

// One generated case: four points from one of nine families, chosen by i.
std::array<XY, 4> make_case(Rng& r, uint64_t i, const std::vector<std::vector<XY>>& circles) {
  std::array<XY, 4> p;
  auto near_line = [&](double lo, double hi) {
    XY a{r.uniform(lo, hi), r.uniform(lo, hi)}, b{r.uniform(lo, hi), r.uniform(lo, hi)};
    double t = r.uniform(-1, 2);
    p = {a, b, nudge(r, {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}), XY{r.uniform(lo, hi), r.uniform(lo, hi)}};
    std::shuffle(p.begin(), p.begin() + 3, r.g);
  };
  auto near_circle = [&](double cx, double cy, double rad) {
    for (auto& q : p) {
      double t = r.uniform(0, 6.283185307179586);
      q = {cx + rad * std::cos(t), cy + rad * std::sin(t)};
    }
    p[3] = nudge(r, p[3]);
  };
  // Exactly co-circular: four lattice points of one circle, or a grid rectangle, scaled by a power of two
  // and moved by an exact offset; counter-clockwise first three most of the time, as a triangulation asks.
  auto lattice = [&](double scale, XY off, bool ulp) {
    if (r.g() % 4 == 0) {
      double x0 = double(r.integer(-50, 50)), y0 = double(r.integer(-50, 50));
      double w = double(r.integer(1, 3)), h = double(r.integer(1, 3));
      p = {XY{x0, y0}, XY{x0 + w, y0}, XY{x0 + w, y0 + h}, XY{x0, y0 + h}};
      std::shuffle(p.begin(), p.end(), r.g);
    } else {
      const auto& c = circles[r.g() % circles.size()];
      size_t idx[4];
      for (int k = 0; k < 4; ++k) {
        bool again;
        do {
          idx[k] = r.g() % c.size();
          again = false;
          for (int j = 0; j < k; ++j) again |= idx[j] == idx[k];
        } while (again);
        p[k] = c[idx[k]];
      }
    }
    for (auto& q : p) q = {off.x + q.x * scale, off.y + q.y * scale};
    if (r.g() % 4 && cdtgpu::pred::orient2d(p[0], p[1], p[2]) < 0) std::swap(p[0], p[1]);
    if (ulp) p[r.g() % 4] = nudge(r, p[r.g() % 4]);
  };
  auto mm = [&](double lo, double hi) { return std::round(r.uniform(lo, hi) * 1000.0) / 1000.0; };
  switch (i % 9) {
    case 0:
      for (auto& q : p) q = {r.uniform(-1e9, 1e9), r.uniform(-1e9, 1e9)};
      break;
    case 1:
      near_line(-1, 1);
      break;
    case 2:
      near_circle(500000.0, 6000000.0, 3.0);
      break;
    case 3:
      for (auto& q : p) q = {double(r.integer(-3, 3)), double(r.integer(-3, 3))};
      break;
    case 4:
      lattice(1.0 / 1024.0, {500000.0, 6000000.0}, false);
      break;
    case 5:
      lattice(0.25, {1000.0, -2000.0}, true);
      break;
    case 6:
      for (auto& q : p) q = {mm(499990, 500010), mm(5999990, 6000010)};
      break;
    case 7:
      if (r.g() & 1) {
        near_circle(3e-50, 1e-50, 1e-50);
      } else {
        lattice(0x1.0p-170, {0, 0}, false);
      }
      break;
    default:
      if (r.g() & 1) {
        near_line(-1e60, 1e60);
      } else {
        lattice(0x1.0p200, {0x1.0p210, -0x1.0p211}, false);
      }
      break;
  }
  return p;
}

bool large() {
  const char* v = std::getenv("CDTGPU_LARGE");
  return v && std::strcmp(v, "1") == 0;
}

TEST(GpuPredicates, MatchCpuAndCgal) {
  using namespace cdtgpu::gpu;
  ContextOptions options;
  options.validation = true;
  Context ctx = create_context(options);
  Pass pass = create_pass(ctx, {"predicates_eval", 2, 0});

  const uint64_t total = large() ? 10'000'000 : 1'000'000;
  const uint64_t batch = 1u << 19;  // 32 MiB of points per dispatch, well below lavapipe's 128 MiB binding
  Buffer quads = create_buffer(ctx, batch * 4 * sizeof(double) * 2, "quads");
  Buffer signs = create_buffer(ctx, batch * 3 * sizeof(int32_t), "signs");
  auto circles = lattice_circles();
  CGAL::Delaunay_triangulation_2<K> dt;
  Rng r(20261122);

  std::vector<double> host(batch * 8);
  std::vector<std::array<XY, 4>> cases(batch);
  uint64_t bad[3] = {0, 0, 0}, cgal_bad = 0, zeros[2] = {0, 0}, cgal_checked = 0;
  for (uint64_t base = 0; base < total; base += batch) {
    uint64_t n = std::min(batch, total - base);
    for (uint64_t k = 0; k < n; ++k) {
      cases[k] = make_case(r, base + k, circles);
      for (int j = 0; j < 4; ++j) {
        host[8 * k + 2 * j] = cases[k][j].x;
        host[8 * k + 2 * j + 1] = cases[k][j].y;
      }
    }
    upload(ctx, quads, host.data(), n * 8 * sizeof(double));
    Recorder rec(ctx);
    rec.dispatch_groups_raw(pass, {Binding(quads, 0, n * 8 * sizeof(double)), Binding(signs, 0, n * 12)}, nullptr,
                            (n + 63) / 64);
    rec.submit();
    auto got = download_vector<int32_t>(ctx, signs, n * 3);
    for (uint64_t k = 0; k < n; ++k) {
      const auto& p = cases[k];
      int want[3] = {cdtgpu::pred::orient2d(p[0], p[1], p[2]), cdtgpu::pred::incircle(p[0], p[1], p[2], p[3]),
                     cdtgpu::pred::incircle_perturbed(p[0], p[1], p[2], p[3])};
      zeros[0] += want[0] == 0;
      zeros[1] += want[1] == 0;
      for (int j = 0; j < 3; ++j) {
        if (got[3 * k + j] != want[j] && ++bad[j] <= 5) {
          ADD_FAILURE() << "case " << base + k << " predicate " << j << ": GPU " << got[3 * k + j] << " CPU "
                        << want[j] << std::hexfloat << " points " << p[0].x << ',' << p[0].y << ' ' << p[1].x
                        << ',' << p[1].y << ' ' << p[2].x << ',' << p[2].y << ' ' << p[3].x << ',' << p[3].y;
        }
      }
      if ((base + k) % 16 == 0) {
        K::Point_2 q[4] = {{p[0].x, p[0].y}, {p[1].x, p[1].y}, {p[2].x, p[2].y}, {p[3].x, p[3].y}};
        int ref[3] = {int(CGAL::orientation(q[0], q[1], q[2])),
                      int(CGAL::side_of_oriented_circle(q[0], q[1], q[2], q[3])),
                      int(dt.side_of_oriented_circle(q[0], q[1], q[2], q[3], true))};
        for (int j = 0; j < 3; ++j) cgal_bad += got[3 * k + j] != ref[j];
        ++cgal_checked;
      }
    }
  }
  EXPECT_EQ(bad[0], 0u) << "orient2d";
  EXPECT_EQ(bad[1], 0u) << "incircle";
  EXPECT_EQ(bad[2], 0u) << "incircle_perturbed";
  EXPECT_EQ(cgal_bad, 0u);
  // The degenerate families must reach the exact stages: many exact zeros.
  EXPECT_GT(zeros[0], total / 100);
  EXPECT_GT(zeros[1], total / 20);
  std::printf("%llu cases per predicate, %llu also checked against CGAL; zero signs: orient2d %llu, incircle %llu\n",
              (unsigned long long)total, (unsigned long long)cgal_checked, (unsigned long long)zeros[0],
              (unsigned long long)zeros[1]);
  EXPECT_TRUE(ctx.messages().empty()) << ctx.messages().front();
}

}  // namespace
