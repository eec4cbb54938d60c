// The DEM grid of a TIN (core/raster): a plane comes back as the plane at every cell, the sample's grid
// equals a brute-force interpolation written here (every triangle tried in order, CGAL's orientation for the
// point-in-triangle test), the first triangle in mesh order wins a shared centre, the grid's extent is the
// bounding box snapped outward, and the ESRI ASCII grid reads back through cdtgpu's own grid reader.
#include "core/raster.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/prepare.hpp"
#include "io/gis_writers.hpp"
#include "io/readers.hpp"
#include "sample_mesh.hpp"

namespace cdtgpu {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

Mesh triangulate(const InputSet& in) { return triangulate_cgal(prepare(in)).mesh; }

const Mesh& katoomba() { return test::katoomba_mesh(); }

// The formula of raster.hpp, written out again.
double plane_through(const Point3& a, const Point3& b, const Point3& c, double x, double y) {
  for (const Point3* v : {&a, &b, &c})
    if (x == v->x && y == v->y) return v->z;
  const double d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  const double s = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / d;
  const double t = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / d;
  return a.z + s * (b.z - a.z) + t * (c.z - a.z);
}

bool inside(const Point3& a, const Point3& b, const Point3& c, double x, double y) {
  const K::Point_2 pa(a.x, a.y), pb(b.x, b.y), pc(c.x, c.y), p(x, y);
  return CGAL::orientation(pa, pb, p) != CGAL::RIGHT_TURN &&
         CGAL::orientation(pb, pc, p) != CGAL::RIGHT_TURN && CGAL::orientation(pc, pa, p) != CGAL::RIGHT_TURN;
}

double brute_force(const Mesh& m, double x, double y) {
  for (const Triangle& t : m.triangles) {
    const Point3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    if (x < std::min({a.x, b.x, c.x}) || x > std::max({a.x, b.x, c.x}) || y < std::min({a.y, b.y, c.y}) ||
        y > std::max({a.y, b.y, c.y}))
      continue;
    if (inside(a, b, c, x, y)) return plane_through(a, b, c, x, y);
  }
  return Raster::nodata;
}

TEST(Raster, APlaneComesBackAsThePlaneAtEveryCell) {
  // Vertices on z = 0.25 x - 0.5 y + 100, coordinates on a 1/8 lattice so z is exact at every vertex;
  // UTM-sized offsets so the rounding of large coordinates is exercised.
  for (double x0 : {0.0, 500000.0}) {
    const double y0 = x0 ? 6000000.0 : 0.0;
    auto plane = [&](double x, double y) { return 0.25 * (x - x0) - 0.5 * (y - y0) + 100; };
    InputSet in;
    uint64_t s = 12345;
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j <= 30; ++j) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        const double x = x0 + i * 2.5 + double((s >> 40) % 9) / 8,
                     y = y0 + j * 3 + double((s >> 20) % 11) / 8;
        in.points.push_back({x, y, plane(x, y)});
      }
    const Mesh m = triangulate(in);
    const Raster r = rasterise(m, 0.5);
    uint64_t filled = 0;
    double worst = 0;
    for (uint64_t row = 0; row < r.spec.nrows; ++row)
      for (uint64_t col = 0; col < r.spec.ncols; ++col) {
        const double z = r.at(row, col);
        if (z == Raster::nodata) continue;
        ++filled;
        const double want = plane(r.spec.x(col), r.spec.y(row));
        // Values lie in [50, 128): measured in ulps of 64 (2^-46); 1 is what the formula reaches here.
        const double ulps = std::fabs(z - want) / std::ldexp(1.0, -46);
        worst = std::max(worst, ulps);
        EXPECT_LE(ulps, 2) << "row " << row << " col " << col << ": " << z << " vs " << want;
      }
    EXPECT_GT(filled, r.spec.ncols * r.spec.nrows * 8 / 10);
    std::printf("plane at x0 = %g: worst error %g ulps of 64\n", x0, worst);
  }
}

TEST(Raster, TheSampleEqualsBruteForceInterpolationAtEveryCell) {
  const Mesh m = katoomba();
  ASSERT_GT(m.triangles.size(), 10000u);
  const Raster r = rasterise(m, 20);
  uint64_t filled = 0, empty = 0;
  for (uint64_t row = 0; row < r.spec.nrows; ++row)
    for (uint64_t col = 0; col < r.spec.ncols; ++col) {
      const double want = brute_force(m, r.spec.x(col), r.spec.y(row));
      ASSERT_EQ(std::bit_cast<uint64_t>(r.at(row, col)), std::bit_cast<uint64_t>(want))
          << "row " << row << " col " << col << ": " << r.at(row, col) << " vs " << want;
      ++(want == Raster::nodata ? empty : filled);
    }
  EXPECT_GT(filled, 5000u);
  EXPECT_GT(empty, 100u);  // the sample's hull is not a rectangle
}

TEST(Raster, AGridDemComesBackUnchangedAtItsOwnCells) {
  // Values of both signs and very different sizes, where a.z + (b.z - a.z) is not always b.z; a NODATA hole.
  std::ostringstream asc;
  asc << "ncols 40\nnrows 30\nxllcenter 300000\nyllcenter 6200000\ncellsize 2\nNODATA_value -9999\n";
  uint64_t s = 77;
  std::vector<double> want;
  for (int r = 0; r < 30; ++r) {
    for (int c = 0; c < 40; ++c) {
      s = s * 6364136223846793005ull + 1442695040888963407ull;
      double z = double(int64_t(s >> 33) % 200001 - 100000) / 997;
      if (c % 7 == 3) z *= 1e-9;
      if (r >= 10 && r < 13 && c >= 20 && c < 24) z = Raster::nodata;
      want.push_back(z);
      char buf[32];
      asc << (c ? " " : "") << std::string(buf, std::to_chars(buf, buf + sizeof buf, z).ptr);
    }
    asc << "\n";
  }
  std::istringstream in(asc.str());
  InputSet dem;
  read_ascii_grid(in, "dem.asc", dem);
  const Raster r = rasterise(triangulate(dem), 2);
  ASSERT_EQ(r.spec.ncols, 40u);
  ASSERT_EQ(r.spec.nrows, 30u);
  EXPECT_EQ(r.spec.x(0), 300000);
  EXPECT_EQ(r.spec.y(29), 6200000);
  for (size_t i = 0; i < want.size(); ++i) {
    if (want[i] == Raster::nodata) continue;  // the hole is triangulated over: interpolated, not NODATA
    EXPECT_EQ(std::bit_cast<uint64_t>(r.z[i]), std::bit_cast<uint64_t>(want[i]))
        << i << ": " << r.z[i] << " vs " << want[i];
  }
}

TEST(Raster, TheGridIsTheBoundingBoxSnappedOutward) {
  const Mesh m = katoomba();
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const Point3& p : m.vertices)
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  for (double cell : {1.0, 7.5, 20.0, 0.3}) {
    const GridSpec g = grid_for(m, cell);
    const double west = g.x(0), east = g.x(g.ncols - 1), south = g.y(g.nrows - 1), north = g.y(0);
    EXPECT_EQ(west, double(g.ix0) * cell);
    EXPECT_EQ(south, double(g.iy0) * cell);
    EXPECT_LE(west, x0);
    EXPECT_GT(double(g.ix0 + 1) * cell, x0);
    EXPECT_GE(east, x1);
    EXPECT_LT(double(g.ix0 + int64_t(g.ncols) - 2) * cell, x1);
    EXPECT_LE(south, y0);
    EXPECT_GT(double(g.iy0 + 1) * cell, y0);
    EXPECT_GE(north, y1);
    EXPECT_LT(double(g.iy0 + int64_t(g.nrows) - 2) * cell, y1);
  }
}

TEST(Raster, TheFirstTriangleInMeshOrderTakesACentreOnItsBoundary) {
  // Two triangles of different heights overlapping on [0, 2] x [0, 2]; centres on the edges count as inside.
  Mesh m;
  m.vertices = {{0, 0, 1}, {4, 0, 1}, {0, 4, 1}, {0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {0, 2, 2}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {3, 5, 6}};
  Raster r = rasterise(m, 1);
  ASSERT_EQ(r.spec.ncols, 5u);
  ASSERT_EQ(r.spec.nrows, 5u);
  EXPECT_EQ(r.at(4, 0), 1);               // (0, 0): a vertex of all three
  EXPECT_EQ(r.at(2, 2), 1);               // (2, 2): on the hypotenuse of the first
  EXPECT_EQ(r.at(0, 4), Raster::nodata);  // (4, 4)
  EXPECT_EQ(r.at(0, 0), 1);               // (0, 4): its corner
  std::swap(m.triangles[0], m.triangles[2]);
  r = rasterise(m, 1);
  EXPECT_EQ(r.at(4, 0), 2);
  EXPECT_EQ(r.at(2, 2), 2);
  EXPECT_EQ(r.at(2, 0), 2);  // (0, 2): corner of the (now first) third triangle
  EXPECT_EQ(r.at(1, 0), 1);  // (0, 3): only the big one
}

TEST(Raster, TheAsciiGridReadsBackThroughCdtgpusReader) {
  const Mesh m = katoomba();
  const Raster r = rasterise(m, 25);
  std::ostringstream out;
  write_ascii_grid(r, out);
  const std::string text = out.str();
  EXPECT_EQ(text.rfind("ncols " + std::to_string(r.spec.ncols) + "\nnrows " + std::to_string(r.spec.nrows) +
                           "\nxllcenter ",
                       0),
            0u);
  std::istringstream in(text);
  InputSet back;
  read_ascii_grid(in, "dem.asc", back);
  size_t k = 0;
  uint64_t nodata = 0;
  for (uint64_t row = 0; row < r.spec.nrows; ++row)
    for (uint64_t col = 0; col < r.spec.ncols; ++col) {
      if (r.at(row, col) == Raster::nodata) {
        ++nodata;
        continue;
      }
      ASSERT_LT(k, back.points.size());
      const Point3& p = back.points[k++];
      EXPECT_EQ(p.x, r.spec.x(col));
      EXPECT_EQ(p.y, r.spec.y(row));
      EXPECT_EQ(std::bit_cast<uint64_t>(p.z), std::bit_cast<uint64_t>(r.at(row, col)));
    }
  EXPECT_EQ(k, back.points.size());
  EXPECT_EQ(back.repairs.nodata_cells, nodata);
  EXPECT_GT(nodata, 0u);
}

TEST(Raster, BadCellSizesAndEmptyMeshesAreRefused) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1000, 0, 0}, {0, 1000, 0}};
  m.triangles = {{0, 1, 2}};
  EXPECT_THROW(grid_for(m, 0), UsageError);
  EXPECT_THROW(grid_for(m, -1), UsageError);
  EXPECT_THROW(grid_for(m, NAN), UsageError);
  EXPECT_THROW(grid_for(m, 1e-3, 1000000), UsageError);  // 10^12 cells
  EXPECT_THROW(grid_for(Mesh{}, 1), std::runtime_error);
}

}  // namespace
}  // namespace cdtgpu
