// Contour lines (core/contours): a plane gives one straight line per level at the closed-form position with
// higher ground on the left; a cone z = r gives one closed ring per level, through the mesh's vertices when
// the level is a ring's height; vertices exactly at a level count as above; the WKT text is exact.
#include "core/contours.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/prepare.hpp"
#include "io/gis_writers.hpp"
#include "sample_mesh.hpp"

namespace cdtgpu {
namespace {

double signed_area(const Points& ring) {
  double a = 0;
  for (size_t i = 0; i + 1 < ring.size(); ++i) a += ring[i].x * ring[i + 1].y - ring[i + 1].x * ring[i].y;
  return a / 2;
}

TEST(Contours, APlaneGivesOneStraightLinePerLevelWithHigherGroundOnTheLeft) {
  auto plane = [](double x, double y) { return 0.3 * x + 0.2 * y + 7; };
  InputSet in;
  uint64_t s = 99;
  for (int i = 0; i <= 30; ++i)
    for (int j = 0; j <= 30; ++j) {
      s = s * 6364136223846793005ull + 1442695040888963407ull;
      const double x = 500000 + i * 10 + double((s >> 40) % 100) / 16,
                   y = 6000000 + j * 10 + double((s >> 20) % 100) / 16;
      in.points.push_back({x, y, plane(x - 500000, y - 6000000)});
    }
  const Mesh m = triangulate_cgal(prepare(in)).mesh;
  double z0 = INFINITY, z1 = -INFINITY;
  for (const Point3& p : m.vertices) z0 = std::min(z0, p.z), z1 = std::max(z1, p.z);
  const std::vector<Contour> lines = contour_lines(m, 5);
  const auto levels = size_t(std::floor(z1 / 5) - std::ceil(z0 / 5) + 1);
  ASSERT_EQ(lines.size(), levels);
  for (size_t k = 0; k < lines.size(); ++k) {
    const Contour& c = lines[k];
    EXPECT_EQ(c.level, (std::ceil(z0 / 5) + double(k)) * 5);
    EXPECT_FALSE(c.closed);
    ASSERT_GE(c.points.size(), 2u);
    for (const Point3& p : c.points) {
      EXPECT_EQ(p.z, c.level);
      EXPECT_NEAR(plane(p.x - 500000, p.y - 6000000), c.level, 1e-9) << p.x << " " << p.y;
    }
    // Along the line (direction perpendicular to the gradient (0.3, 0.2)), higher ground on the left.
    const double dx = c.points.back().x - c.points.front().x, dy = c.points.back().y - c.points.front().y;
    EXPECT_GT(-dy * 0.3 + dx * 0.2, 0) << "level " << c.level;
    for (size_t i = 1; i < c.points.size(); ++i) {
      const double ex = c.points[i].x - c.points[i - 1].x, ey = c.points[i].y - c.points[i - 1].y;
      EXPECT_GT(ex * dx + ey * dy, 0) << "level " << c.level << " point " << i << ": the line turns back";
    }
  }
}

// Centre z = 0, rings of radius k = 1..6 with z = k, n points each at the same angles; triangles between
// rings.
Mesh cone(uint32_t n) {
  Mesh m;
  m.vertices.push_back({0, 0, 0});
  for (int k = 1; k <= 6; ++k)
    for (uint32_t i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      m.vertices.push_back({k * std::cos(a), k * std::sin(a), double(k)});
    }
  auto v = [&](int k, uint32_t i) { return k == 0 ? 0u : 1 + uint32_t(k - 1) * n + i % n; };
  auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    const Point3 &p = m.vertices[a], &q = m.vertices[b], &r = m.vertices[c];
    if ((q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x) < 0) std::swap(b, c);
    m.triangles.push_back({a, b, c});
  };
  for (uint32_t i = 0; i < n; ++i) add(v(0, 0), v(1, i), v(1, i + 1));
  for (int k = 1; k < 6; ++k)
    for (uint32_t i = 0; i < n; ++i) {
      add(v(k, i), v(k, i + 1), v(k + 1, i + 1));
      add(v(k, i), v(k + 1, i + 1), v(k + 1, i));
    }
  return m;
}

TEST(Contours, AConeGivesRingsOnTheCirclesThroughItsVertices) {
  const uint32_t n = 24;
  const std::vector<Contour> lines = contour_lines(cone(n), 1);
  // Level 0: only the apex, which counts as above: nothing below, no line.
  ASSERT_EQ(lines.size(), 6u);
  for (size_t k = 0; k < 6; ++k) {
    const Contour& c = lines[k];
    EXPECT_EQ(c.level, double(k + 1));
    EXPECT_TRUE(c.closed);
    ASSERT_EQ(c.points.size(), n + 1) << "level " << c.level << ": the ring's vertices, each once";
    EXPECT_EQ(c.points.front(), c.points.back());
    for (const Point3& p : c.points) {
      EXPECT_NEAR(std::hypot(p.x, p.y), c.level, 1e-13 * c.level);
      EXPECT_EQ(p.z, c.level);
    }
    EXPECT_LT(signed_area(c.points), 0) << "a pit: higher ground outside, on the left, so clockwise";
  }
}

TEST(Contours, BetweenRingsTheLineCrossesEveryEdgeOnce) {
  const uint32_t n = 16;
  const Mesh m = cone(n);
  const std::vector<Contour> lines = contour_lines(m, 0.5);
  // Levels 0.5 .. 6 by 0.5: the whole ones as above, the half ones from 1.5 cross n radial and n diagonal
  // edges, 0.5 only the n radial edges of the fan around the apex.
  ASSERT_EQ(lines.size(), 12u);
  for (const Contour& c : lines) {
    EXPECT_TRUE(c.closed);
    const bool half = c.level != std::floor(c.level) && c.level > 1;
    EXPECT_EQ(c.points.size(), (half ? 2 * n : n) + 1) << c.level;
    for (size_t i = 0; i < c.points.size(); ++i) {
      const double r = std::hypot(c.points[i].x, c.points[i].y);
      // Radial edges (every other point, from the first) cross at radius exactly the level; diagonal ones
      // a little inside it.
      if (!half || i % 2 == 0) {
        EXPECT_NEAR(r, c.level, 1e-13 * c.level) << c.level << " " << i;
      } else {
        EXPECT_LT(r, c.level) << c.level << " " << i;
      }
    }
  }
}

TEST(Contours, VerticesAtTheLevelCountAsAbove) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {0, 1, 0}, {1, 0, 10}, {1, 1, 10}};
  m.triangles = {{0, 2, 3}, {0, 3, 1}};
  const std::vector<Contour> lines = contour_lines(m, 5);
  ASSERT_EQ(lines.size(), 2u);
  // z = 0 everywhere above 0 or at it: no line at 0. At 5: the middle, higher ground (+x) on the left,
  // through the crossing of the diagonal.
  EXPECT_EQ(lines[0].level, 5);
  EXPECT_EQ(lines[0].points, (Points{{0.5, 1, 5}, {0.5, 0.5, 5}, {0.5, 0, 5}}));
  // At 10 the line runs along the edge whose ends are at the level, through the vertices themselves.
  EXPECT_EQ(lines[1].level, 10);
  EXPECT_EQ(lines[1].points, (Points{{1, 1, 10}, {1, 0, 10}}));
  std::ostringstream out;
  write_contours_wkt(lines, out);
  EXPECT_EQ(out.str(), "LINESTRING Z (0.5 1 5, 0.5 0.5 5, 0.5 0 5)\nLINESTRING Z (1 1 10, 1 0 10)\n");
}

TEST(Contours, AFlatMeshAndAnIsolatedPeakAtTheLevelGiveNoLines) {
  Mesh m;
  m.vertices = {{0, 0, 10}, {2, 0, 10}, {1, 2, 10}};
  m.triangles = {{0, 1, 2}};
  EXPECT_TRUE(contour_lines(m, 10).empty());
  // A peak exactly at 10 among lower neighbours: the line shrinks to a point and is dropped.
  Mesh p;
  p.vertices = {{0, 0, 0}, {2, 0, 0}, {1, 1, 10}, {1, 2, 0}};
  p.triangles = {{0, 1, 2}, {1, 3, 2}, {3, 0, 2}};
  const std::vector<Contour> lines = contour_lines(p, 10);
  EXPECT_TRUE(lines.empty());
}

TEST(Contours, GeoJsonCarriesTheLevelsTheLinesAndTheEpsgCode) {
  const std::vector<Contour> lines = contour_lines(cone(12), 0.5);
  Crs crs;
  crs.epsg = 7855;
  std::ostringstream out;
  write_contours_geojson(lines, crs, out);
  const nlohmann::json j = nlohmann::json::parse(out.str());
  EXPECT_EQ(j["type"], "FeatureCollection");
  EXPECT_EQ(j["crs"]["properties"]["name"], "urn:ogc:def:crs:EPSG::7855");
  ASSERT_EQ(j["features"].size(), lines.size());
  for (size_t k = 0; k < lines.size(); ++k) {
    const auto& f = j["features"][k];
    EXPECT_EQ(f["properties"]["level"].get<double>(), lines[k].level);
    EXPECT_EQ(f["properties"]["closed"].get<bool>(), lines[k].closed);
    EXPECT_EQ(f["geometry"]["type"], "LineString");
    const auto& xyz = f["geometry"]["coordinates"];
    ASSERT_EQ(xyz.size(), lines[k].points.size());
    for (size_t i = 0; i < xyz.size(); ++i)
      EXPECT_EQ((Point3{xyz[i][0].get<double>(), xyz[i][1].get<double>(), xyz[i][2].get<double>()}),
                lines[k].points[i]);
  }
  std::ostringstream none;
  write_contours_geojson({}, Crs{}, none);
  EXPECT_EQ(nlohmann::json::parse(none.str())["features"].size(), 0u);
  EXPECT_FALSE(nlohmann::json::parse(none.str()).contains("crs"));
}

// The sample has its contour lines' vertices exactly at multiples of 10: many vertices sit on the levels.
TEST(Contours, OnTheSampleLinesEndOnlyOnTheMeshBoundaryAndRingsClose) {
  const Mesh& m = test::katoomba_mesh();
  // Boundary edges: those of one triangle only.
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (const Triangle& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++uses[std::minmax(t[e], t[(e + 1) % 3])];
  std::vector<std::pair<Point3, Point3>> boundary;
  for (const auto& [e, n] : uses)
    if (n == 1) boundary.push_back({m.vertices[e.first], m.vertices[e.second]});
  auto distance_to_boundary = [&](const Point3& p) {
    double best = INFINITY;
    for (const auto& [a, b] : boundary) {
      const double dx = b.x - a.x, dy = b.y - a.y;
      const double t = std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
      best = std::min(best, std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy));
    }
    return best;
  };
  for (double interval : {10.0, 5.0, 2.5}) {
    const std::vector<Contour> lines = contour_lines(m, interval);
    ASSERT_FALSE(lines.empty());
    size_t open = 0, closed = 0;
    for (size_t k = 0; k < lines.size(); ++k) {
      const Contour& c = lines[k];
      if (k) {
        EXPECT_LE(lines[k - 1].level, c.level);
      }
      for (size_t i = 1; i < c.points.size(); ++i) EXPECT_NE(c.points[i], c.points[i - 1]);
      if (c.closed) {
        ++closed;
        EXPECT_EQ(c.points.front(), c.points.back());
      } else {
        ++open;
        EXPECT_LT(distance_to_boundary(c.points.front()), 1e-6) << "level " << c.level << " starts inside";
        EXPECT_LT(distance_to_boundary(c.points.back()), 1e-6) << "level " << c.level << " ends inside";
      }
    }
    EXPECT_GT(open, 10u);
    EXPECT_GT(closed, 2u);
  }
}

TEST(Contours, BadIntervalsAreRefused) {
  const Mesh m = cone(8);
  EXPECT_THROW(contour_lines(m, 0), UsageError);
  EXPECT_THROW(contour_lines(m, -1), UsageError);
  EXPECT_THROW(contour_lines(m, INFINITY), UsageError);
  EXPECT_THROW(contour_lines(m, 1e-9), UsageError);
  EXPECT_TRUE(contour_lines(Mesh{}, 1).empty());
}

}  // namespace
}  // namespace cdtgpu
