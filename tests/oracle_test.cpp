// Tests of the reference path: prepare, canonicalize, the CGAL CDT and verify (that it accepts CGAL's
// results and catches broken meshes).
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "core/canonical.hpp"
#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/repair.hpp"
#include "core/verify.hpp"
#include "core/workloads.hpp"

namespace cdtgpu {
namespace {

Polyline line(Points pts, bool closed = false) {
  Polyline l;
  l.points = std::move(pts);
  l.closed = closed;
  return l;
}

std::string failures(const VerifyReport& r) {
  std::string s;
  for (const std::string& f : r.failures) s += "  " + f + "\n";
  return s;
}

// prepare -> CGAL -> verify; the test fails with verify's messages.
CdtResult triangulate_and_verify(const InputSet& in, PreparedInput* prepared_out = nullptr) {
  PreparedInput p = prepare(in);
  CdtResult r = triangulate_cgal(p);
  VerifyReport report = verify_mesh(r.mesh, p);
  EXPECT_TRUE(report.ok()) << failures(report);
  EXPECT_EQ(report.steiner_vertices, r.steiner_points);
  if (prepared_out) *prepared_out = std::move(p);
  return r;
}

double signed_area(const Mesh& m, const Triangle& t) {
  const Point3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

bool has_edge(const Mesh& m, uint32_t a, uint32_t b) {
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if ((t[k] == a && t[(k + 1) % 3] == b) || (t[k] == b && t[(k + 1) % 3] == a)) return true;
  return false;
}

uint32_t index_of(const Mesh& m, double x, double y) {
  for (uint32_t i = 0; i < m.vertices.size(); ++i)
    if (m.vertices[i].x == x && m.vertices[i].y == y) return i;
  ADD_FAILURE() << "no vertex at (" << x << ", " << y << ")";
  return 0;
}

InputSet grid(int n, double spacing = 1.0) {
  InputSet in;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) in.points.push_back({i * spacing, j * spacing, double((i * 7 + j * 3) % 11)});
  return in;
}

// ---------------------------------------------------------------------------------------------------------------
// prepare

TEST(Prepare, MergesDuplicatesAndFirstZWins) {
  InputSet in;
  in.points = {{0, 0, 1}, {1, 0, 2}, {0, 0, 5}, {0, 0, 1}};
  in.lines.push_back(line({{1, 0, 7}, {2, 2, 3}}));
  PreparedInput p = prepare(in);
  ASSERT_EQ(p.vertices.size(), 3u);
  EXPECT_EQ(p.vertices[0], (Point3{0, 0, 1}));  // z of the first occurrence, not the later 5
  EXPECT_EQ(p.vertices[1], (Point3{1, 0, 2}));  // loose points come before line vertices
  EXPECT_EQ(p.vertices[2], (Point3{2, 2, 3}));
  EXPECT_EQ(p.input_points, 6u);
  EXPECT_EQ(p.merged_duplicates, 3u);
  EXPECT_EQ(p.z_conflicts, 2u);  // (0,0): 1 vs 5; (1,0): 2 vs 7. The repeated (0,0,1) is no conflict.
  EXPECT_EQ(p.max_z_conflict, 5.0);
  ASSERT_EQ(p.constraints.size(), 1u);
  EXPECT_EQ(p.constraints[0], (Edge{1, 2}));
  EXPECT_EQ(p.constraint_line[0], 0u);
}

// The vertices prepare shows ahead (the CLI writes the mesh file's vertex section from them) are the ones it
// returns, in the same storage, shown once; nothing is abandoned on success.
TEST(Prepare, ShowsItsFinalVerticesAheadInTheirOwnStorage) {
  InputSet in;
  in.points = {{3, 1, 1}, {0, 0, 2}, {3, 1, 9}};
  in.lines.push_back(line({{1, 1, 0}, {2, 5, 0}, {0, 0, 4}}));
  int shown = 0, abandoned = 0;
  const Point3* at = nullptr;
  Points copy;
  VerticesAhead ahead;
  ahead.made = [&](const Points& v) {
    ++shown;
    at = v.data();
    copy.assign(v.begin(), v.end());
  };
  ahead.abandoned = [&] { ++abandoned; };
  const PreparedInput p = prepare(in, {}, {}, ahead);
  EXPECT_EQ(shown, 1);
  EXPECT_EQ(abandoned, 0);
  EXPECT_EQ(at, p.vertices.data());
  EXPECT_EQ(copy, p.vertices);
  EXPECT_EQ(p.vertices.size(), 4u);
  EXPECT_EQ(p.constraints.size(), 2u);
}

TEST(Prepare, SortsVerticesLexicographically) {
  InputSet in;
  in.points = {{3, 1, 0}, {1, 5, 0}, {1, -2, 0}, {-4, 9, 0}, {3, 0, 0}};
  PreparedInput p = prepare(in);
  ASSERT_EQ(p.vertices.size(), 5u);
  Points expect = {{-4, 9, 0}, {1, -2, 0}, {1, 5, 0}, {3, 0, 0}, {3, 1, 0}};
  EXPECT_EQ(p.vertices, expect);
  EXPECT_EQ(p.merged_duplicates, 0u);
  EXPECT_EQ(p.input_segments, 0u);
}

TEST(Prepare, RingClosingEdgeSharedEdgesAndCounts) {
  InputSet in;
  // Square ring (closing edge implied) and a second ring sharing the edge (1,0)-(1,1), walked the other way.
  in.lines.push_back(line({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, true));
  in.lines.push_back(line({{1, 1, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}}, true));
  in.lines.push_back(line({{0, 0, 0}, {2, 1, 0}, {0, 1, 0}}));  // open: 2 segments, no closing edge
  PreparedInput p = prepare(in);
  // Vertices: (0,0)=0 (0,1)=1 (1,0)=2 (1,1)=3 (2,0)=4 (2,1)=5
  ASSERT_EQ(p.vertices.size(), 6u);
  EXPECT_EQ(p.input_segments, 10u);
  EXPECT_EQ(p.duplicate_segments, 1u);
  EXPECT_EQ(p.zero_length_segments, 0u);
  std::vector<Edge> expect = {{0, 1}, {0, 2}, {0, 5}, {1, 3}, {1, 5}, {2, 3}, {2, 4}, {3, 5}, {4, 5}};
  EXPECT_EQ(p.constraints, expect);
  // The shared edge (2,3) keeps the first ring; the closing edge (0,1) of ring 0 is there.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> from;
  for (size_t i = 0; i < p.constraints.size(); ++i)
    from[{p.constraints[i][0], p.constraints[i][1]}] = p.constraint_line[i];
  EXPECT_EQ((from[{2, 3}]), 0u);
  EXPECT_EQ((from[{0, 1}]), 0u);
  EXPECT_EQ((from[{2, 4}]), 1u);
  EXPECT_EQ((from[{3, 5}]), 1u);
  EXPECT_EQ((from[{0, 5}]), 2u);
  EXPECT_EQ(p.merged_duplicates, 11u - 6u);
}

TEST(Prepare, DropsZeroLengthSegmentsOfUnrepairedLines) {
  InputSet in;
  // Built by hand, not through add_polyline, so the repeated vertex is still there.
  in.lines.push_back(line({{0, 0, 0}, {0, 0, 1}, {1, 1, 0}}));
  PreparedInput p = prepare(in);
  EXPECT_EQ(p.input_segments, 2u);
  EXPECT_EQ(p.zero_length_segments, 1u);
  ASSERT_EQ(p.constraints.size(), 1u);
  EXPECT_EQ(p.z_conflicts, 1u);
}

// ---------------------------------------------------------------------------------------------------------------
// canonicalize

TEST(Canonicalize, SortsVerticesAndTrianglesKeepingOrientation) {
  Mesh m;
  m.vertices = {{2, 0, 0}, {0, 0, 0}, {2, 2, 0}, {0, 2, 0}};  // sorted: (0,0) (0,2) (2,0) (2,2)
  m.triangles = {{2, 3, 0}, {1, 0, 3}};                       // both CCW, not rotated to the smallest
  canonicalize(m);
  Points vs = {{0, 0, 0}, {0, 2, 0}, {2, 0, 0}, {2, 2, 0}};
  EXPECT_EQ(m.vertices, vs);
  // old 2->3, 3->1, 0->2, 1->0: {3,1,2} -> {1,2,3}; {0,2,1} -> {0,2,1}
  Triangles ts = {{0, 2, 1}, {1, 2, 3}};
  EXPECT_EQ(m.triangles, ts);
  for (const Triangle& t : m.triangles) EXPECT_GT(signed_area(m, t), 0);
}

TEST(Canonicalize, IsIdempotentAndOrderIndependent) {
  InputSet in = uniform_points(300, 5);
  CdtResult r = triangulate_cgal(prepare(in));
  Mesh shuffled = r.mesh;
  std::mt19937_64 rng(9);
  std::vector<uint32_t> perm(shuffled.vertices.size());
  for (uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  Points vs(perm.size());
  for (uint32_t i = 0; i < perm.size(); ++i) vs[perm[i]] = shuffled.vertices[i];
  shuffled.vertices = vs;
  for (Triangle& t : shuffled.triangles) {
    t = {perm[t[1]], perm[t[2]], perm[t[0]]};
  }
  std::shuffle(shuffled.triangles.begin(), shuffled.triangles.end(), rng);
  canonicalize(shuffled);
  EXPECT_EQ(shuffled.vertices, r.mesh.vertices);
  EXPECT_EQ(shuffled.triangles, r.mesh.triangles);
  Mesh again = r.mesh;
  canonicalize(again);
  EXPECT_EQ(again.triangles, r.mesh.triangles);
}

// A tile's counting sort gives the parallel sort's order: rotated, shuffled triangles of a real mesh.
TEST(Canonicalize, OneCoreCountingSortEqualsTheSort) {
  InputSet in = uniform_points(5000, 6);
  const CdtResult r = triangulate_cgal(prepare(in));
  Triangles mixed = r.mesh.triangles;
  std::mt19937_64 rng(3);
  for (Triangle& t : mixed) std::rotate(t.begin(), t.begin() + rng() % 3, t.end());
  std::shuffle(mixed.begin(), mixed.end(), rng);
  Triangles counted = mixed;
  canonicalize_triangles_one_core(counted, r.mesh.vertices.size());
  canonicalize_triangles(mixed);
  EXPECT_EQ(counted, r.mesh.triangles);
  EXPECT_EQ(mixed, r.mesh.triangles);
  Triangles none;
  canonicalize_triangles_one_core(none, 0);
  EXPECT_TRUE(none.empty());
}

// ---------------------------------------------------------------------------------------------------------------
// CGAL CDT + verify on valid inputs

TEST(CgalCdt, UniformPointsWithNonCrossingConstraints) {
  InputSet in = uniform_points(20000, 11);
  add_dt_edge_constraints(in, 3000, 0.2, 12);
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_EQ(r.steiner_points, 0u);
  EXPECT_EQ(r.mesh.vertices, p.vertices);
  // Every constraint of dt-edges ends on input points and crosses none, so each one is exactly split into
  // mesh edges; at least every constraint is there.
  VerifyReport v = verify_mesh(r.mesh, p);
  EXPECT_GE(v.constrained_edges, p.constraints.size());
  // Euler for a triangulation of n points with h hull points: 2n - 2 - h triangles.
  EXPECT_GT(r.mesh.triangles.size(), 2 * p.vertices.size() - 200);
}

TEST(CgalCdt, SameInputSameMesh) {
  InputSet in = uniform_points(3000, 3);
  add_dt_edge_constraints(in, 400, 0.1, 4);
  PreparedInput p = prepare(in);
  CdtResult a = triangulate_cgal(p), b = triangulate_cgal(p);
  EXPECT_EQ(a.mesh.vertices, b.mesh.vertices);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
}

TEST(CgalCdt, GridDemIsValidAndCoCircularEverywhere) {
  CdtResult r = triangulate_and_verify(grid(60));
  EXPECT_EQ(r.mesh.vertices.size(), 3600u);
  EXPECT_EQ(r.mesh.triangles.size(), 2u * 59 * 59);
}

// The plain Delaunay triangulation uses the same perturbation, so without constraints the sets are equal.
TEST(CgalCdt, GridWithoutConstraintsEqualsPlainDelaunay) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
  using Dt = CGAL::Delaunay_triangulation_2<K, CGAL::Triangulation_data_structure_2<Vb>>;
  for (int n : {7, 40}) {
    PreparedInput p = prepare(grid(n, 0.5));
    CdtResult r = triangulate_cgal(p);
    std::vector<std::pair<K::Point_2, uint32_t>> pts;
    for (uint32_t i = 0; i < p.vertices.size(); ++i)
      pts.push_back({K::Point_2(p.vertices[i].x, p.vertices[i].y), i});
    std::reverse(pts.begin(), pts.end());  // another insertion order than the CDT's, same answer
    Dt dt(pts.begin(), pts.end());
    Mesh m;
    m.vertices = p.vertices;
    for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
      m.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    canonicalize(m);
    EXPECT_EQ(m.vertices, r.mesh.vertices);
    EXPECT_EQ(m.triangles, r.mesh.triangles) << "grid " << n;
  }
}

TEST(CgalCdt, GridWithContourLikeConstraints) {
  InputSet in = grid(41);
  // Diamonds through grid nodes (diagonal segments between nodes).
  for (int r : {4, 8, 12}) {
    in.lines.push_back(
        line({{20.0 + r, 20, 1}, {20, 20.0 + r, 1}, {20.0 - r, 20, 1}, {20, 20.0 - r, 1}}, true));
  }
  // A long straight contour through many grid nodes (above the circles): split at every node it passes.
  in.lines.push_back(line({{1, 39, 5}, {39, 39, 5}}));
  // Off-grid circles (vertices between nodes), like real contours.
  for (double radius : {15.3, 17.7}) {
    Polyline c;
    c.closed = true;
    for (int k = 0; k < 90; ++k) {
      const double a = 2 * std::numbers::pi * k / 90;
      c.points.push_back({20 + radius * std::cos(a), 20 + radius * std::sin(a), radius});
    }
    in.lines.push_back(c);
  }
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_EQ(r.steiner_points, 0u);
  EXPECT_EQ(r.mesh.vertices.size(), 41u * 41 + 180);
  // The horizontal contour y = 39 is 38 mesh edges.
  for (int x = 1; x < 39; ++x)
    EXPECT_TRUE(has_edge(r.mesh, index_of(r.mesh, x, 39), index_of(r.mesh, x + 1, 39)));
}

TEST(CgalCdt, TerrainWorkloadDemWithContours) {
  TerrainOptions o;
  o.grid = 60;
  o.levels = 10;
  InputSet in = terrain_workload(o);
  ASSERT_FALSE(in.lines.empty());
  CdtResult r = triangulate_and_verify(in);
  EXPECT_EQ(r.steiner_points, 0u);
}

TEST(CgalCdt, ManyDuplicateIntegerPoints) {
  InputSet in;
  std::mt19937_64 rng(17);
  for (int i = 0; i < 5000; ++i)
    in.points.push_back({double(rng() % 25), double(rng() % 25), double(rng() % 3)});
  in.lines.push_back(line({{0, 0, 0}, {24, 24, 0}}));  // through every diagonal node
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_EQ(p.vertices.size(), r.mesh.vertices.size());
  EXPECT_LE(p.vertices.size(), 625u);
  EXPECT_EQ(p.merged_duplicates, 5002u - p.vertices.size());
  EXPECT_GT(p.z_conflicts, 0u);
}

TEST(CgalCdt, FewOrCollinearVerticesGiveNoTriangles) {
  for (int n : {0, 1, 2}) {
    InputSet in;
    for (int i = 0; i < n; ++i) in.points.push_back({double(i), 2.0 * i, 0});
    CdtResult r = triangulate_and_verify(in);
    EXPECT_TRUE(r.mesh.triangles.empty());
    EXPECT_EQ(r.mesh.vertices.size(), size_t(n));
  }
  InputSet in;
  for (int i = 0; i < 10; ++i) in.points.push_back({double(i), 2.0 * i + 1, 0});
  in.lines.push_back(line({{0, 1, 0}, {9, 19, 0}}));  // along the line, through every point
  CdtResult r = triangulate_and_verify(in);
  EXPECT_TRUE(r.mesh.triangles.empty());
  EXPECT_EQ(r.mesh.vertices.size(), 10u);
}

TEST(CgalCdt, CollinearPointsOnTheHull) {
  InputSet in;
  for (int i = 0; i <= 10; ++i) {
    in.points.push_back({double(i), 0, 0});
    in.points.push_back({double(i), 10, 0});
    in.points.push_back({0, double(i), 0});
    in.points.push_back({10, double(i), 0});
  }
  in.points.push_back({3.5, 4.25, 1});
  in.points.push_back({6.5, 7.75, 1});
  CdtResult r = triangulate_and_verify(in);
  // 40 boundary points (all on the hull), 2 inside: 2n - 2 - h triangles.
  EXPECT_EQ(r.mesh.vertices.size(), 42u);
  EXPECT_EQ(r.mesh.triangles.size(), 2u * 42 - 2 - 40);
}

TEST(CgalCdt, CrossingConstraintsGetInterpolatedSteinerVertex) {
  InputSet in;
  in.lines.push_back(line({{0, 4, 10}, {4, 0, 2}}));
  in.lines.push_back(line({{0, 0, 0}, {4, 4, 8}}));
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  // Constraints sorted: (0,0)-(4,4) is constraint 0, so the crossing's z follows it: 0 + 0.5 * 8.
  ASSERT_EQ(p.constraints.size(), 2u);
  EXPECT_EQ(r.steiner_points, 1u);
  ASSERT_EQ(r.mesh.vertices.size(), 5u);
  EXPECT_EQ(r.mesh.vertices[index_of(r.mesh, 2, 2)].z, 4.0);
  EXPECT_EQ(r.mesh.triangles.size(), 4u);
}

TEST(CgalCdt, SeveralCrossingsWithInexactIntersections) {
  InputSet in;
  in.points = {{-1, -1, 0}, {11, -1, 0}, {11, 11, 0}, {-1, 11, 0}};
  in.lines.push_back(line({{0, 0, 0}, {10, 3, 3}}));
  in.lines.push_back(line({{0, 3, 6}, {7, 0, 0}}));
  in.lines.push_back(line({{1, 10, 0}, {9.5, 0.1, 9}}));
  in.lines.push_back(line({{0.2, 9, 0}, {10, 9.7, 1}, {0.3, 0.1, 2}}));
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_EQ(r.steiner_points, 5u);  // A-B, A-C, C-D1, D2-B, D2-C
  // A and B cross at (70/17, 21/17): the exact point rounded to the nearest doubles (IEEE division is exactly
  // that). A, starting at the lowest vertex (0,0), is the lower-indexed constraint: z = 3 * 7/17 along it.
  const Point3& ab = r.mesh.vertices[index_of(r.mesh, 70.0 / 17, 21.0 / 17)];
  EXPECT_NEAR(ab.z, 21.0 / 17, 1e-12);
  // Every Steiner z lies between the z of the ends of some constraint (interpolated, not invented).
  for (const Point3& v : r.mesh.vertices) {
    bool input = std::any_of(p.vertices.begin(), p.vertices.end(),
                             [&](const Point3& q) { return q.x == v.x && q.y == v.y; });
    if (input) continue;
    EXPECT_GE(v.z, 0.0);
    EXPECT_LE(v.z, 9.0);
  }
}

TEST(CgalCdt, ManyRandomCrossingConstraintsFarFromTheOrigin) {
  // Thousands of Steiner points at UTM-like coordinates, where rounding the crossings matters most.
  InputSet in = uniform_points(2000, 31);
  std::mt19937_64 rng(32);
  for (int i = 0; i < 150; ++i) {
    Polyline l;
    for (int k = 0; k < 2; ++k)
      l.points.push_back({kUniformX0 + unit_double(rng) * kUniformSide,
                          kUniformY0 + unit_double(rng) * kUniformSide, unit_double(rng) * 100});
    in.lines.push_back(l);
  }
  CdtResult r = triangulate_and_verify(in);
  EXPECT_GT(r.steiner_points, 1000u);
}

TEST(CgalCdt, ConstraintThroughAnExistingVertexIsSplitThere) {
  InputSet in;
  in.points = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {2, 2, 7}, {1, 3, 0}};
  in.lines.push_back(line({{0, 0, 0}, {4, 4, 0}}));
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_EQ(r.steiner_points, 0u);
  const uint32_t c = index_of(r.mesh, 2, 2);
  EXPECT_TRUE(has_edge(r.mesh, index_of(r.mesh, 0, 0), c));
  EXPECT_TRUE(has_edge(r.mesh, c, index_of(r.mesh, 4, 4)));
  EXPECT_EQ(verify_mesh(r.mesh, p).constrained_edges, 2u);
  EXPECT_EQ(r.mesh.vertices[c].z, 7.0);
}

TEST(CgalCdt, ConstraintOverridesThePerturbedDiagonal) {
  // Four co-circular points: the perturbation picks one diagonal; a constraint on the other must win.
  InputSet in;
  in.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  CdtResult plain = triangulate_and_verify(in);
  const bool has_main = has_edge(plain.mesh, index_of(plain.mesh, 0, 0), index_of(plain.mesh, 1, 1));
  if (has_main)
    in.lines.push_back(line({{1, 0, 0}, {0, 1, 0}}));
  else
    in.lines.push_back(line({{0, 0, 0}, {1, 1, 0}}));
  PreparedInput p;
  CdtResult r = triangulate_and_verify(in, &p);
  EXPECT_NE(has_main, has_edge(r.mesh, index_of(r.mesh, 0, 0), index_of(r.mesh, 1, 1)));
  // Without its constraint, the same mesh is not the (perturbed) Delaunay triangulation.
  p.constraints.clear();
  EXPECT_FALSE(verify_mesh(r.mesh, p).ok());
}

// ---------------------------------------------------------------------------------------------------------------
// verify catches broken meshes

struct Broken : ::testing::Test {
  void SetUp() override {
    InputSet in = uniform_points(2000, 21);
    add_dt_edge_constraints(in, 300, 0.2, 22);
    prepared = prepare(in);
    mesh = triangulate_cgal(prepared).mesh;
    ASSERT_TRUE(verify_mesh(mesh, prepared).ok());
    ASSERT_EQ(mesh.vertices, prepared.vertices);  // no Steiner points: constraint indices are mesh indices
    for (const Edge& e : prepared.constraints) constrained.insert({e[0], e[1]});
  }

  bool is_constraint(uint32_t a, uint32_t b) const {
    return constrained.count({std::min(a, b), std::max(a, b)}) > 0;
  }

  // Flips the first interior edge (convex quad) for which want(constrained) holds; returns false if none.
  bool flip_edge(bool want_constrained) {
    std::map<std::pair<uint32_t, uint32_t>, std::pair<size_t, uint32_t>>
        half;  // (a,b) -> (triangle, opposite)
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const Triangle& tr = mesh.triangles[t];
        half[{tr[k], tr[(k + 1) % 3]}] = {t, tr[(k + 2) % 3]};
      }
    for (const auto& [ab, tc] : half) {
      const auto [a, b] = ab;
      if (a > b || is_constraint(a, b) != want_constrained) continue;
      auto it = half.find({b, a});
      if (it == half.end()) continue;
      const uint32_t c = tc.second, d = it->second.second;
      Mesh m = mesh;
      m.triangles[tc.first] = {a, d, c};
      m.triangles[it->second.first] = {d, b, c};
      if (signed_area(m, m.triangles[tc.first]) <= 0 || signed_area(m, m.triangles[it->second.first]) <= 0)
        continue;
      mesh = m;
      return true;
    }
    return false;
  }

  bool fails_with(const std::string& text) {
    VerifyReport r = verify_mesh(mesh, prepared);
    for (const std::string& f : r.failures)
      if (f.find(text) != std::string::npos) return true;
    ADD_FAILURE() << "expected a failure containing '" << text << "', got:\n" << failures(r);
    return false;
  }

  PreparedInput prepared;
  Mesh mesh;
  std::set<std::pair<uint32_t, uint32_t>> constrained;
};

TEST_F(Broken, FlippedDelaunayEdgeFails) {
  ASSERT_TRUE(flip_edge(false));
  EXPECT_TRUE(fails_with("not locally Delaunay"));
}

TEST_F(Broken, FlippedConstraintEdgeFails) {
  ASSERT_TRUE(flip_edge(true));
  EXPECT_TRUE(fails_with("is not covered by mesh edges"));
}

TEST_F(Broken, DroppedTriangleFails) {
  mesh.triangles.erase(mesh.triangles.begin() + mesh.triangles.size() / 2);
  EXPECT_TRUE(fails_with("V - E + F"));
  EXPECT_TRUE(fails_with("boundary"));
}

TEST_F(Broken, ReversedTriangleFails) {
  Triangle& t = mesh.triangles[mesh.triangles.size() / 3];
  std::swap(t[1], t[2]);
  EXPECT_TRUE(fails_with("is clockwise"));
}

TEST_F(Broken, DuplicateTriangleAndBadIndexFail) {
  Mesh saved = mesh;
  mesh.triangles.push_back(mesh.triangles.front());
  EXPECT_TRUE(fails_with("are the same triangle"));
  mesh = saved;
  mesh.triangles.back()[2] = uint32_t(mesh.vertices.size());
  EXPECT_TRUE(fails_with("out of range"));
}

TEST_F(Broken, MissingOrMovedVertexFails) {
  prepared.vertices.push_back({1e7, 1e7, 0});  // an input vertex the mesh does not have
  EXPECT_TRUE(fails_with("is not in the mesh"));
  prepared.vertices.pop_back();
  mesh.vertices[5].z += 1;
  EXPECT_TRUE(fails_with("has z"));
}

TEST_F(Broken, ExtraVertexIsNotASteinerPoint) {
  // A new vertex inside a triangle, fanned: a valid triangulation, but the vertex is not an input vertex nor
  // a constraint crossing.
  const Triangle t = mesh.triangles[0];
  const Point3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
  const uint32_t v = uint32_t(mesh.vertices.size());
  mesh.vertices.push_back({(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, 0});
  mesh.triangles[0] = {t[0], t[1], v};
  mesh.triangles.push_back({t[1], t[2], v});
  mesh.triangles.push_back({t[2], t[0], v});
  EXPECT_TRUE(fails_with("not an input vertex and not a crossing of constraints"));
}

// verify_mesh resolves the constraints by the rules, which need the vertices sorted: a hand-made input in
// another order (vertices shuffled, constraints reversed and shuffled) is checked the same.
TEST(Verify, PreparedInputInAnyOrder) {
  InputSet in = uniform_points(500, 31);
  in.lines.push_back(line({{0.1, 0.1, 0}, {0.9, 0.8, 1}}));
  in.lines.push_back(line({{0.1, 0.9, 2}, {0.8, 0.05, 3}}));  // crosses the first
  const PreparedInput p = prepare(in);
  const CdtResult r = triangulate_cgal(p);
  ASSERT_EQ(r.steiner_points, 1u);
  std::mt19937_64 rng(4);
  std::vector<uint32_t> perm(p.vertices.size());
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), rng);
  PreparedInput q = p;
  for (uint32_t i = 0; i < perm.size(); ++i) q.vertices[perm[i]] = p.vertices[i];
  for (Edge& e : q.constraints) e = {perm[e[1]], perm[e[0]]};
  std::shuffle(q.constraints.begin(), q.constraints.end(), rng);
  const VerifyReport v = verify_mesh(r.mesh, q);
  EXPECT_TRUE(v.ok()) << failures(v);
  EXPECT_EQ(v.steiner_vertices, 1u);
}

TEST(Verify, NoTrianglesForNonCollinearInputFails) {
  InputSet in;
  in.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  PreparedInput p = prepare(in);
  Mesh m;
  m.vertices = p.vertices;
  VerifyReport r = verify_mesh(m, p);
  EXPECT_FALSE(r.ok());
}

TEST(Verify, MissingHullTriangleOnCollinearBoundaryFails) {
  // A square with a point on its bottom edge; leave out the triangle on that edge's left half: the boundary
  // then cuts inside the hull.
  InputSet in;
  in.points = {{0, 0, 0}, {2, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};
  PreparedInput p = prepare(in);
  CdtResult r = triangulate_cgal(p);
  ASSERT_TRUE(verify_mesh(r.mesh, p).ok());
  const uint32_t a = index_of(r.mesh, 0, 0), b = index_of(r.mesh, 2, 0);
  size_t before = r.mesh.triangles.size();
  std::erase_if(r.mesh.triangles, [&](const Triangle& t) {
    for (int k = 0; k < 3; ++k)
      if (t[k] == a && t[(k + 1) % 3] == b) return true;
    return false;
  });
  ASSERT_EQ(r.mesh.triangles.size(), before - 1);
  EXPECT_FALSE(verify_mesh(r.mesh, p).ok());
}

}  // namespace
}  // namespace cdtgpu
