// The GPU's derived outputs (gpu/raster, gpu/contours) against the CPU's (core/raster, core/contours): the
// same doubles at every cell, bit for bit, and the same contour text, byte for byte. Inputs: the bundled
// Katoomba sample at several cell sizes and intervals; a grid DEM with noisy z whose cell centres fall
// exactly on its vertices and on the edges shared by two triangles (the tie rule decides which triangle's
// rounding a centre gets); the same mesh with a hole cut out (NODATA inside); the grid in bands of a few
// rows against the grid in one band; contour segments in small chunks against one chunk. The correctly
// rounded division (shaders/division.glsl) is checked from quotients a few ulps off, a correction the
// device's own division may never need. Validation layer on; any message fails the test.
#include <gtest/gtest.h>

#include <cstdlib>

#include <bit>
#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/cdt_cgal.hpp"
#include "core/contours.hpp"
#include "core/predicates.hpp"
#include "core/prepare.hpp"
#include "core/raster.hpp"
#include "gpu/buffers.hpp"
#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "gpu/contours.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/raster.hpp"
#include "gpu/recorder.hpp"
#include "gpu/tin.hpp"
#include "io/gis_writers.hpp"
#include "gpu_test_context.hpp"
#include "sample_mesh.hpp"

namespace cdtgpu {
namespace {

using test::ctx;
using test::no_validation_messages;

const gpu::Primitives& prims() {
  static gpu::Primitives p(ctx());
  return p;
}

const gpu::GpuRasteriser& rasteriser() {
  static gpu::GpuRasteriser r(ctx(), prims());
  return r;
}

const gpu::GpuContourer& contourer() {
  static gpu::GpuContourer c(ctx(), prims());
  return c;
}


// Every cell's bits equal; the first difference is reported.
void expect_same_grid(const Raster& got, const Raster& want, const std::string& what) {
  ASSERT_EQ(got.spec.ncols, want.spec.ncols) << what;
  ASSERT_EQ(got.spec.nrows, want.spec.nrows) << what;
  ASSERT_EQ(got.z.size(), want.z.size()) << what;
  for (size_t i = 0; i < want.z.size(); ++i)
    ASSERT_EQ(std::bit_cast<uint64_t>(got.z[i]), std::bit_cast<uint64_t>(want.z[i]))
        << what << ": cell " << i << " (row " << i / want.spec.ncols << ", col " << i % want.spec.ncols
        << "): gpu " << got.z[i] << ", cpu " << want.z[i];
}

std::string wkt_of(const std::vector<Contour>& lines) {
  std::ostringstream out;
  write_contours_wkt(lines, out);
  return out.str();
}

std::string geojson_of(const std::vector<Contour>& lines) {
  std::ostringstream out;
  write_contours_geojson(lines, Crs{}, out);
  return out.str();
}

// A (2n+1) x (2n+1) grid DEM at integer x, y from 1000, 2000, with noisy z of varied magnitude and sign (so
// the two triangles of a shared edge round a centre on it differently), triangulated by CGAL.
Mesh noisy_grid(int n) {
  InputSet in;
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j) {
      const double r = std::hypot(i, j);
      in.points.push_back({1000.0 + i, 2000.0 + j, 300 * std::cos(r / 4) + 7 * u(rng) + (i * j) * 1e-3});
    }
  return triangulate_cgal(prepare(in)).mesh;
}

// Centres of a grid of the mesh's own cells lie on two or more triangles: how many of them get a different
// double from the largest-index triangle holding them than from the smallest (the test is only as good as
// this number is large).
size_t centres_where_the_tie_matters(const Mesh& m, double cell) {
  const Raster r = rasterise(m, cell);
  size_t differ = 0;
  for (uint64_t row = 0; row < r.spec.nrows; ++row)
    for (uint64_t col = 0; col < r.spec.ncols; ++col) {
      const pred::XY p{r.spec.x(col), r.spec.y(row)};
      double last = Raster::nodata;
      bool found = false;
      for (const Triangle& t : m.triangles) {
        const Point3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
        if (p.x < std::min({a.x, b.x, c.x}) || p.x > std::max({a.x, b.x, c.x}) ||
            p.y < std::min({a.y, b.y, c.y}) || p.y > std::max({a.y, b.y, c.y}))
          continue;
        if (pred::orient2d({a.x, a.y}, {b.x, b.y}, p) < 0 || pred::orient2d({b.x, b.y}, {c.x, c.y}, p) < 0 ||
            pred::orient2d({c.x, c.y}, {a.x, a.y}, p) < 0)
          continue;
        last = interpolate(a, b, c, p.x, p.y);
        found = true;
      }
      if (found && std::bit_cast<uint64_t>(last) != std::bit_cast<uint64_t>(r.at(row, col))) ++differ;
    }
  return differ;
}

TEST(GpuDivision, CoarseQuotientsAreCorrectedToTheNearest) {
  const char* v = std::getenv("CDTGPU_VALIDATION");  // =0 where the layer is not installed (the H100 machine)
  if (!(v && std::string(v) == "0")) {
    EXPECT_TRUE(ctx().validation) << "the Khronos validation layer is not active";
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> mant(1, 2);
  std::uniform_int_distribution<int> expo(-60, 60), sign(0, 1);
  auto value = [&] { return (sign(rng) ? -1 : 1) * std::ldexp(mant(rng), expo(rng)); };
  std::vector<double> cases, want;
  for (int i = 0; i < 4000; ++i) {
    const double a = value(), b = value(), q = a / b;
    const int off = i % 7 - 3;  // -3 .. 3 ulps
    double q0 = q;
    for (int k = 0; k < std::abs(off); ++k) q0 = std::nextafter(q0, off > 0 ? INFINITY : -INFINITY);
    cases.insert(cases.end(), {a, b, q0});
    want.push_back(q);
  }
  // Quotients as coarse as Vulkan allows (single precision's 2.5 ulp): the Newton steps' work.
  for (int i = 0; i < 1000; ++i) {
    const double a = value(), b = value(), q = a / b;
    cases.insert(cases.end(), {a, b, q * (1 + (i % 5 - 2) * 1.2e-7)});
    want.push_back(q);
  }
  // Quotients whose exact value lies very close to a midpoint: a = b * (q + half an ulp) rounded.
  for (int i = 0; i < 1000; ++i) {
    const double b = value(), q = value();
    const double mid = q + (std::nextafter(q, INFINITY) - q) / 2;
    const double a = b * mid;
    cases.insert(cases.end(), {a, b, std::nextafter(a / b, -INFINITY)});
    want.push_back(a / b);
  }
  // Zero over either sign: a zero of the sign IEEE gives, whatever the device's quotient says.
  for (double a : {0.0, -0.0})
    for (double b : {3.0, -3.0}) {
      cases.insert(cases.end(), {a, b, 0.0});
      want.push_back(a / b);
    }
  gpu::Pass eval = gpu::create_pass(ctx(), {"division_eval", 2, 0});
  gpu::Buffer in = gpu::upload_new(ctx(), cases, "division cases");
  gpu::Buffer out = gpu::create_buffer(ctx(), want.size() * 8, "division quotients");
  gpu::Recorder rec(ctx());
  rec.dispatch_groups_raw(eval, {in, out}, nullptr, (want.size() + 63) / 64);
  rec.submit();
  const std::vector<double> got = gpu::download_vector<double>(ctx(), out, want.size());
  for (size_t i = 0; i < want.size(); ++i)
    ASSERT_EQ(std::bit_cast<uint64_t>(got[i]), std::bit_cast<uint64_t>(want[i]))
        << "case " << i << ": " << cases[3 * i] << " / " << cases[3 * i + 1] << " from " << cases[3 * i + 2]
        << ": gpu " << got[i] << ", cpu " << want[i];
  no_validation_messages();
}

TEST(GpuRaster, TheSampleEqualsTheCpuGridBitForBit) {
  const Mesh& m = test::katoomba_mesh();
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  for (double cell : {20.0, 3.7, 1.0}) {
    const GridSpec spec = grid_for(m, cell);
    const Raster want = rasterise(m, spec);
    expect_same_grid(rasteriser().rasterise(tin, spec), want, "sample, cell " + std::to_string(cell));
    size_t filled = 0;
    for (double z : want.z) filled += z != Raster::nodata;
    EXPECT_GT(filled, want.z.size() / 2) << cell;
    EXPECT_LT(filled, want.z.size()) << cell;  // the hull is not a rectangle
  }
  no_validation_messages();
}

TEST(GpuRaster, CentresOnVerticesAndSharedEdgesGoToTheSameTriangleAsOnTheCpu) {
  const Mesh m = noisy_grid(20);
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  // 1: every centre a vertex; 0.5: edge midpoints and square centres (on the diagonals); 0.25 and 0.125: more
  // of both, and centres strictly inside.
  for (double cell : {1.0, 0.5, 0.25, 0.125})
    expect_same_grid(rasteriser().rasterise(tin, grid_for(m, cell)), rasterise(m, cell),
                     "grid DEM, cell " + std::to_string(cell));
  EXPECT_GT(centres_where_the_tie_matters(m, 0.5), 200u);
  no_validation_messages();
}

TEST(GpuRaster, AHoleInTheMeshIsNodataOnBoth) {
  Mesh m = noisy_grid(20);
  // Drop the triangles of the square 995..1004 x 1995..2006, as regions would.
  std::erase_if(m.triangles, [&](const Triangle& t) {
    for (uint32_t v : t)
      if (m.vertices[v].x < 995 || m.vertices[v].x > 1004 || m.vertices[v].y < 1995 || m.vertices[v].y > 2006)
        return false;
    return true;
  });
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  for (double cell : {1.0, 0.5, 0.3}) {
    const Raster want = rasterise(m, cell);
    expect_same_grid(rasteriser().rasterise(tin, grid_for(m, cell)), want,
                     "holed grid, cell " + std::to_string(cell));
    // The hole's middle is NODATA, its rim (on the remaining triangles' edges) is not.
    const GridSpec& g = want.spec;
    const uint64_t col = uint64_t(std::llround(1000 / cell)) - uint64_t(g.ix0);
    const uint64_t row = uint64_t(g.iy0 + int64_t(g.nrows) - 1 - std::llround(2000 / cell));
    EXPECT_EQ(want.at(row, col), Raster::nodata) << cell;
  }
  EXPECT_NE(rasterise(m, 1.0).at(uint64_t(2020 - 1995), uint64_t(995 - 980)), Raster::nodata);
  no_validation_messages();
}

TEST(GpuRaster, BandsOfAFewRowsEqualOneBand) {
  const Mesh& m = test::katoomba_mesh();
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  const GridSpec spec = grid_for(m, 4.0);
  const Raster whole = rasteriser().rasterise(tin, spec);
  expect_same_grid(whole, rasterise(m, spec), "one band");
  for (uint64_t rows : {1u, 7u, 100u})
    expect_same_grid(rasteriser().rasterise(tin, spec, spec.ncols * rows + 3), whole,
                     std::to_string(rows) + "-row bands");
  EXPECT_THROW(rasteriser().rasterise(tin, spec, spec.ncols - 1), gpu::DeviceError);  // a row must fit a band
  const Mesh g = noisy_grid(12);
  const gpu::DeviceTin gt = gpu::upload_tin(ctx(), g);
  expect_same_grid(rasteriser().rasterise(gt, grid_for(g, 0.5), grid_for(g, 0.5).ncols * 3),
                   rasterise(g, 0.5), "grid DEM in 3-row bands");
  no_validation_messages();
}

TEST(GpuContours, TheSampleGivesTheCpuTextByteForByte) {
  const Mesh& m = test::katoomba_mesh();
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  for (double interval : {10.0, 5.0, 2.5, 0.7}) {
    const std::vector<Contour> want = contour_lines(m, interval);
    ASSERT_FALSE(want.empty());
    const std::vector<Contour> got = contourer().lines(tin, m, interval);
    EXPECT_EQ(wkt_of(got), wkt_of(want)) << interval;
    EXPECT_EQ(geojson_of(got), geojson_of(want)) << interval;
    // Segments in chunks of at most 500: the same lines.
    EXPECT_EQ(wkt_of(contourer().lines(tin, m, interval, 100000, 500)), wkt_of(want)) << interval;
  }
  no_validation_messages();
}

TEST(GpuContours, VerticesOnTheLevelsGiveTheCpuText) {
  // Integer z on a grid: many vertices exactly at the levels (they count as above), lines through vertices.
  InputSet in;
  for (int i = 0; i <= 30; ++i)
    for (int j = 0; j <= 30; ++j)
      in.points.push_back({double(i), double(j), std::round(10 * std::sin(i / 5.0) * std::cos(j / 7.0))});
  const Mesh m = triangulate_cgal(prepare(in)).mesh;
  const gpu::DeviceTin tin = gpu::upload_tin(ctx(), m);
  for (double interval : {1.0, 0.5, 3.0}) {
    const std::vector<Contour> want = contour_lines(m, interval);
    ASSERT_FALSE(want.empty());
    EXPECT_EQ(wkt_of(contourer().lines(tin, m, interval)), wkt_of(want)) << interval;
  }
  const Mesh noisy = noisy_grid(15);
  const gpu::DeviceTin nt = gpu::upload_tin(ctx(), noisy);
  EXPECT_EQ(wkt_of(contourer().lines(nt, noisy, 13.0, 100000, 64)), wkt_of(contour_lines(noisy, 13.0)));
  no_validation_messages();
}

}  // namespace
}  // namespace cdtgpu
