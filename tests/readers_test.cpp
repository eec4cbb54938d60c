// Readers on small real files: the WKT/CSV/ASC files in tests/data/readers, shapefiles written here with
// shapelib's own writer, and damaged copies of them (truncated, corrupt, missing companions).
#include "io/readers.hpp"

#include <gtest/gtest.h>
#include <shapefil.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/drape.hpp"
#include "core/error.hpp"
#include "io/input_spec.hpp"

using namespace cdtgpu;
namespace fs = std::filesystem;

namespace {

const std::string kData = std::string(CDTGPU_SOURCE_DIR) + "/tests/data/readers/";

// Runs f, expects an InputError whose message contains `part` and whose record is `record`.
void expect_input_error(const std::function<void()>& f, const std::string& part, uint64_t record) {
  try {
    f();
    ADD_FAILURE() << "no InputError; expected one containing '" << part << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << "message: " << e.what();
    EXPECT_EQ(e.record, record) << "message: " << e.what();
  }
}

InputSet wkt(const std::string& text) {
  InputSet in;
  std::istringstream s(text);
  read_wkt(s, "t.wkt", in);
  return in;
}

InputSet xyz(const std::string& text) {
  InputSet in;
  std::istringstream s(text);
  read_xyz(s, "t.xyz", in);
  return in;
}

InputSet grid(const std::string& text) {
  InputSet in;
  std::istringstream s(text);
  read_ascii_grid(s, "t.asc", in);
  return in;
}

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("readers_test_" + std::to_string(getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }
  fs::path dir_;
};

// One shape for write_shapefile: parts are start indices; null writes a NULL shape.
struct Shape {
  std::vector<int> parts;
  std::vector<double> x, y, z;
  bool null = false;
};

// Writes base.shp/.shx and, when elev is given, base.dbf with fields ID and ELEV (one value per shape).
void write_shapefile(const std::string& base, int type, const std::vector<Shape>& shapes,
                     const std::vector<double>* elev = nullptr) {
  SHPHandle shp = SHPCreate(base.c_str(), type);
  ASSERT_NE(shp, nullptr);
  for (const Shape& s : shapes) {
    SHPObject* o = s.null
                       ? SHPCreateSimpleObject(SHPT_NULL, 0, nullptr, nullptr, nullptr)
                       : SHPCreateObject(type, -1, int(s.parts.size()),
                                         s.parts.empty() ? nullptr : s.parts.data(), nullptr, int(s.x.size()),
                                         s.x.data(), s.y.data(), s.z.empty() ? nullptr : s.z.data(), nullptr);
    ASSERT_NE(o, nullptr);
    EXPECT_GE(SHPWriteObject(shp, -1, o), 0);
    SHPDestroyObject(o);
  }
  SHPClose(shp);
  if (!elev) return;
  DBFHandle dbf = DBFCreate((base + ".dbf").c_str());
  ASSERT_NE(dbf, nullptr);
  ASSERT_EQ(DBFAddField(dbf, "ID", FTInteger, 10, 0), 0);
  ASSERT_EQ(DBFAddField(dbf, "ELEV", FTDouble, 12, 3), 1);
  for (size_t i = 0; i < elev->size(); ++i) {
    EXPECT_TRUE(DBFWriteIntegerAttribute(dbf, int(i), 0, int(i) + 1));
    EXPECT_TRUE(DBFWriteDoubleAttribute(dbf, int(i), 1, (*elev)[i]));
  }
  DBFClose(dbf);
}

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Contours: ArcZ, record 1 one part, record 2 two parts, record 3 NULL. ELEV differs from the geometry's z.
void write_contours(const std::string& base) {
  const std::vector<double> elev = {100.5, 200.25, 0};
  write_shapefile(
      base, SHPT_ARCZ,
      {Shape{{0}, {0, 1, 2}, {0, 1, 0}, {1, 1, 1}},
       Shape{{0, 2}, {5, 6, 7, 8, 9}, {5, 5, 6, 6, 6}, {2, 2, 3, 3, 3}}, Shape{{}, {}, {}, {}, true}},
      &elev);
}

}  // namespace

// ---- WKT ----

TEST(Wkt, ReadsEveryTypeWithAndWithoutZ) {
  InputSet in;
  read_input(kData + "mixed.wkt", {}, in);
  ASSERT_EQ(in.sources.size(), 1u);
  EXPECT_EQ(in.sources[0], kData + "mixed.wkt");
  const Points points = {{1, 2, 3}, {4, 5, 0}, {0, 0, 0}, {1, 0, 0}, {2, 2, 7}, {3, 3, 8}};
  EXPECT_EQ(in.points, points);
  ASSERT_EQ(in.lines.size(), 9u);
  struct Want {
    uint64_t record;
    size_t n;
    bool closed;
  };
  const Want want[] = {{6, 3, false}, {7, 2, false}, {8, 2, false}, {8, 2, false}, {9, 4, true},
                       {9, 3, true},  {11, 3, true}, {11, 3, true}, {13, 2, false}};
  for (size_t i = 0; i < 9; ++i) {
    EXPECT_EQ(in.lines[i].record, want[i].record) << i;
    EXPECT_EQ(in.lines[i].points.size(), want[i].n) << i;
    EXPECT_EQ(in.lines[i].closed, want[i].closed) << i;
    EXPECT_EQ(in.lines[i].source, 0u);
  }
  EXPECT_EQ(in.lines[1].points, (Points{{0, 0, 1}, {5, 5, 2}}));  // repeated vertex removed
  EXPECT_EQ(in.lines[4].points[2], (Point3{4, 4, 10}));                        // POLYGON Z keeps its z
  EXPECT_EQ(in.lines[8].points, (Points{{0, 0, 1}, {1, 1, 2}}));  // ZM: m dropped
  EXPECT_EQ(in.repairs.repeated_vertices, 1u);
  EXPECT_EQ(in.repairs.rings_closed, 1u);  // the second MULTIPOLYGON ring did not repeat its first vertex
}

TEST(Wkt, SuffixDimensionsCollectionsAndSrid) {
  InputSet in =
      wkt("POINTZ (1 2 3)\n"
          "SRID=4326;POINT M (1 2 7)\n"
          "GEOMETRYCOLLECTION (POINT (9 9), LINESTRING Z (0 0 1, 1 0 2))\n"
          "MULTIPOINT (EMPTY, (5 5))\n"
          "POINT (1e-3 +2.5)\n");
  EXPECT_EQ(in.points, (Points{{1, 2, 3}, {1, 2, 0}, {9, 9, 0}, {5, 5, 0}, {1e-3, 2.5, 0}}));
  ASSERT_EQ(in.lines.size(), 1u);
  EXPECT_EQ(in.lines[0].record, 3u);
}

TEST(Wkt, MalformedLineNamesItsLine) {
  expect_input_error([] { wkt("POINT (1 2)\n\nLINESTRING (1 2, 3)\n"); },
                     "t.wkt:3: expected 2 numbers in a coordinate, found 1", 3);
  expect_input_error([] { wkt("POINT (1)\n"); }, "t.wkt:1: expected 2 to 4 numbers in a coordinate, found 1",
                     1);
  expect_input_error([] { wkt("POINT (1 2)\nPOINT (1 x)\n"); }, "expected a number, found 'x'", 2);
  expect_input_error([] { wkt("CIRCLE (1 2)\n"); }, "unknown geometry type 'CIRCLE'", 1);
  expect_input_error([] { wkt("POINT Z (1 2)\n"); }, "expected 3 numbers", 1);
  expect_input_error([] { wkt("POINT (1 2) junk\n"); }, "unknown geometry type 'JUNK'", 1);
  expect_input_error([] { wkt("POINT (1 2\n"); }, "expected ')', found end of input", 1);
  // A missing comma is not taken for an XYZM coordinate.
  expect_input_error([] { wkt("POINT (9 9)\nPOLYGON ((0 0, 1 0, 1 1 0 0))\n"); },
                     "expected 2 numbers in a coordinate, found 4", 2);
  // An unclosed '(' runs into the next line: the message names both lines.
  expect_input_error([] { wkt("POINT (0 0)\nLINESTRING (1 2, 3 4\nPOINT (5 6)\n"); },
                     "t.wkt:3: expected ')', found 'POINT' (geometry starts at line 2)", 3);
}

TEST(Wkt, GeometrySpanningLines) {
  InputSet in = wkt("\nPOLYGON (\n  (0 0, 1 0,\n   1 1, 0 0)\n)\nPOINT (3 3)\n");
  ASSERT_EQ(in.lines.size(), 1u);
  EXPECT_EQ(in.lines[0].record, 2u);
  EXPECT_EQ(in.lines[0].points.size(), 3u);
  EXPECT_TRUE(in.lines[0].closed);
  EXPECT_EQ(in.points, (Points{{3, 3, 0}}));
  expect_input_error([] { wkt("LINESTRING (0 0,\n 1 nan)\n"); },
                     "not a finite number (geometry starts at line 1)", 2);
}

TEST(Wkt, NonFiniteCoordinates) {
  expect_input_error([] { wkt("POINT (0 0)\nPOINT (nan 1)\n"); }, "not a finite number", 2);
  expect_input_error([] { wkt("LINESTRING Z (0 0 0, 1 1 inf)\n"); }, "not a finite number", 1);
  expect_input_error([] { wkt("POLYGON ((0 0, 1 0, -infinity 1, 0 0))\n"); }, "not a finite number", 1);
  expect_input_error([] { wkt("POINT (1e999 0)\n"); }, "out of range", 1);
}

TEST(Wkt, StdinDash) {
  std::istringstream text("POINT (1 2)\nLINESTRING (0 0, 1 1)\n");
  std::streambuf* old = std::cin.rdbuf(text.rdbuf());
  InputSet in;
  read_input("-", {}, in);
  std::cin.rdbuf(old);
  EXPECT_EQ(in.sources, std::vector<std::string>{"<stdin>"});
  EXPECT_EQ(in.points.size(), 1u);
  EXPECT_EQ(in.lines.size(), 1u);
}

TEST(Wkt, RepairsRingNotClosedAndRepeatedVertices) {
  InputSet in = wkt("POLYGON ((0 0, 0 0, 1 0, 1 1, 1 1))\nLINESTRING (2 2, 2 2)\n");
  ASSERT_EQ(in.lines.size(), 1u);
  EXPECT_EQ(in.lines[0].points, (Points{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
  EXPECT_EQ(in.repairs.repeated_vertices, 3u);
  EXPECT_EQ(in.repairs.rings_closed, 1u);
  EXPECT_EQ(in.repairs.degenerate_lines, 1u);  // LINESTRING (2 2, 2 2) kept as a point
  EXPECT_EQ(in.points, (Points{{2, 2, 0}}));
}

// ---- XYZ / CSV ----

TEST(Xyz, HeaderCommentsSeparatorsAndExtraColumns) {
  InputSet in;
  read_input(kData + "points.csv", {}, in);
  EXPECT_EQ(in.points, (Points{{1.5, 2.5, 3.5}, {-1000, 2, 0.1}, {4, 5, 6}}));
  EXPECT_TRUE(in.lines.empty());
}

TEST(Xyz, BadLinesNameTheirLine) {
  expect_input_error([] { xyz("1 2 3\n4 5\n"); }, "t.xyz:2: expected x y z, found 2 numbers", 2);
  expect_input_error([] { xyz("x y z\n1 2 3\nx y z\n"); }, "column 1 is not a number: 'x'", 3);
  expect_input_error([] { xyz("1,,3\n"); }, "t.xyz:1: column 2 is empty", 1);
  expect_input_error([] { xyz("1 2 3abc\n"); }, "column 3 is not a number: '3abc'", 1);
  expect_input_error([] { xyz("# c\n1 2 3\n1 2 nan\n"); }, "not a finite number", 3);
  expect_input_error([] { xyz("inf 2 3\n"); }, "not a finite number", 1);
  expect_input_error([] { xyz("1 2 1e400\n"); }, "out of range", 1);
}

TEST(Xyz, ManyLinesRoundTripExactly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> d(-1e7, 1e7);
  Points want(200000);
  std::string text;
  char buf[96];
  for (Point3& p : want) {
    p = {d(rng), d(rng), d(rng) * 1e-4};
    std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
    text += buf;
  }
  InputSet in = xyz(text);
  EXPECT_EQ(in.points, want);
}

// ---- ESRI ASCII grid ----

TEST(AsciiGrid, CornerOriginAndNodata) {
  InputSet in;
  read_input(kData + "grid_corner.asc", {}, in);
  EXPECT_EQ(in.points,
            (Points{{105, 215, 1}, {115, 215, 2}, {125, 215, 3}, {105, 205, 4}, {125, 205, 6}}));
  EXPECT_EQ(in.repairs.nodata_cells, 1u);
}

TEST(AsciiGrid, CenterOriginWithDxDy) {
  InputSet in;
  read_input(kData + "grid_center.asc", {}, in);
  EXPECT_EQ(in.points, (Points{{0.5, 2.5, 1}, {1.5, 2.5, 2}, {0.5, 0.5, 3}, {1.5, 0.5, 4}}));
  EXPECT_EQ(in.repairs.nodata_cells, 0u);
}

TEST(AsciiGrid, WrappedRowsAreAccepted) {
  InputSet in = grid("ncols 4\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n7 8\n");
  ASSERT_EQ(in.points.size(), 8u);
  EXPECT_EQ(in.points[4], (Point3{0.5, 0.5, 5}));
}

TEST(AsciiGrid, WrongValueCountsNameTheLine) {
  const std::string h = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
  expect_input_error([&] { grid(h + "1 2 3\n4 5\n"); }, "row 2 has 2 values, ncols is 3", 7);
  expect_input_error([&] { grid(h + "1 2 3\n4 5 6\n7 8 9\n"); }, "more values than ncols x nrows = 6", 8);
  expect_input_error([&] { grid(h + "1 2\n3 4\n"); }, "expected ncols x nrows = 6 values, found 4", 7);
  expect_input_error([&] { grid(h + "1 2 3\n4 x 6\n"); }, "not a number: 'x'", 7);
  expect_input_error([&] { grid(h + "1 2 3\n4 nan 6\n"); }, "not a finite number", 7);
  expect_input_error([&] { grid(h + "1 2 3\n4 -inf 6\n"); }, "not a finite number", 7);
  expect_input_error([] { grid("ncols 3\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3\n"); },
                     "lacks yllcorner|yllcenter", 5);
  expect_input_error([] { grid("ncols 3\nnrows 2\nxllcorner inf\n"); }, "xllcorner must be a finite number",
                     3);
  expect_input_error([] { grid("ncols -3\n"); }, "ncols must be a positive integer", 1);
  expect_input_error([] { grid("ncols 3\nbanana 4\n"); }, "unknown header key 'banana'", 2);
}

TEST(AsciiGrid, AllNodataIsNoGeometry) {
  expect_input_error(
      [] { grid("ncols 2\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\nnodata_value -1\n-1 -1\n"); },
      "no geometry", 0);
}

// ---- dispatch and whole-file errors ----

class Inputs : public TempDir {};

TEST_F(Inputs, ExtensionIsCaseInsensitive) {
  write("A.WKT", "POINT (1 2)\n");
  write("b.Xyz", "1 2 3\n");
  write("c.TXT", "4 5 6\n");
  write("d.ASC", "ncols 1\nnrows 1\nxllcenter 0\nyllcenter 0\ncellsize 1\n7\n");
  InputSet in;
  for (const char* f : {"A.WKT", "b.Xyz", "c.TXT", "d.ASC"}) read_input(path(f), {}, in);
  EXPECT_EQ(in.points, (Points{{1, 2, 0}, {1, 2, 3}, {4, 5, 6}, {0, 0, 7}}));
  ASSERT_EQ(in.sources.size(), 4u);
  EXPECT_EQ(in.sources[3], path("d.ASC"));
}

TEST_F(Inputs, UnknownExtensionMissingFileAndEmptyInput) {
  write("x.e57", "1 2 3\n");
  InputSet in;
  expect_input_error([&] { read_input(path("x.e57"), {}, in); }, "x.e57: unknown input format '.e57'", 0);
  expect_input_error([&] { read_input(path("nothing.wkt"), {}, in); }, "nothing.wkt: no such file", 0);
  expect_input_error([&] { read_input(path("nothing.shp"), {}, in); }, "nothing.shp: no such file", 0);
  for (const char* f : {"e.wkt", "e.csv", "e.asc"}) {
    write(f, "\n\n");
    expect_input_error([&] { read_input(path(f), {}, in); }, std::string(f) + ": no geometry", 0);
  }
  write("comments.xyz", "x y z\n# nothing here\n");
  expect_input_error([&] { read_input(path("comments.xyz"), {}, in); }, "no geometry", 0);
  write("empty.wkt", "POINT EMPTY\n");
  expect_input_error([&] { read_input(path("empty.wkt"), {}, in); }, "no geometry", 0);
}

// ---- shapefiles ----

class Shapefile : public TempDir {};

TEST_F(Shapefile, PointZWithNullShapeAndPrj) {
  write_shapefile(path("pts"), SHPT_POINTZ,
                  {Shape{{}, {1}, {2}, {3}}, Shape{{}, {}, {}, {}, true}, Shape{{}, {4}, {5}, {6}}});
  write("pts.prj", "PROJCS[\"GDA2020 / MGA zone 55\"]\r\n");
  InputSet in;
  read_input(path("pts.shp"), {}, in);
  EXPECT_EQ(in.points, (Points{{1, 2, 3}, {4, 5, 6}}));
  EXPECT_EQ(in.repairs.null_shapes, 1u);
  EXPECT_EQ(in.source_crs_wkt, "PROJCS[\"GDA2020 / MGA zone 55\"]");
  EXPECT_EQ(in.sources, std::vector<std::string>{path("pts.shp")});
  // A second .prj does not replace the first one seen.
  write_shapefile(path("more"), SHPT_MULTIPOINT, {Shape{{}, {7, 8}, {7, 8}, {}}});
  write("more.prj", "GEOGCS[\"WGS 84\"]");
  read_input(path("more.shp"), {}, in);
  EXPECT_EQ(in.points.size(), 4u);
  EXPECT_EQ(in.points[3], (Point3{8, 8, 0}));
  EXPECT_EQ(in.source_crs_wkt, "PROJCS[\"GDA2020 / MGA zone 55\"]");
}

TEST_F(Shapefile, ArcZTakesZFromGeometryOrFromTheZField) {
  write_contours(path("contours"));
  InputSet geo;
  read_input(path("contours.shp"), {}, geo);
  ASSERT_EQ(geo.lines.size(), 3u);
  EXPECT_EQ(geo.lines[0].points, (Points{{0, 0, 1}, {1, 1, 1}, {2, 0, 1}}));
  EXPECT_EQ(geo.lines[2].points, (Points{{7, 6, 3}, {8, 6, 3}, {9, 6, 3}}));
  EXPECT_EQ(geo.lines[1].record, 2u);
  EXPECT_EQ(geo.lines[2].record, 2u);
  EXPECT_FALSE(geo.lines[0].closed);
  EXPECT_EQ(geo.repairs.null_shapes, 1u);

  InputSet attr;
  read_input(path("contours.shp"), {.z_field = "elev"}, attr);  // field names match case-insensitively
  ASSERT_EQ(attr.lines.size(), 3u);
  for (const Point3& p : attr.lines[0].points) EXPECT_EQ(p.z, 100.5);
  for (const Point3& p : attr.lines[2].points) EXPECT_EQ(p.z, 200.25);
  EXPECT_EQ(attr.lines[2].points[0].x, 7.0);

  // Alone, a Z shapefile without the field is an error listing its fields (it used to keep its z silently)...
  InputSet alone;
  expect_input_error([&] { read_input(path("contours.shp"), {.z_field = "HEIGHT"}, alone); },
                     "no field HEIGHT in " + path("contours.dbf") + " (fields: ID, ELEV)", 0);
  // ... read along with a shapefile that has the field, it keeps its own z (footprints read with contours).
  write_shapefile(path("roofz"), SHPT_ARCZ, {Shape{{0}, {20, 21}, {0, 0}, {7, 7}}});  // no .dbf
  InputSet both;
  read_inputs({path("contours.shp"), path("roofz.shp")}, {.z_field = "ELEV"}, both);
  EXPECT_EQ(both.lines.front().points[0].z, 100.5);
  EXPECT_EQ(both.lines.back().points[0].z, 7.0);
  InputSet neither;
  expect_input_error([&] { read_inputs({path("contours.shp"), path("roofz.shp")}, {.z_field = "HEIGHT"}, neither); },
                     "no input shapefile has the z field HEIGHT", 0);
}

// A Z shapefile read without a z field has every vertex's z (InputPart::z_complete): drape skips it. A 2D one,
// or one under a z field (whose attribute may be null), does not.
TEST_F(Shapefile, ZShapefilesHaveEveryZ) {
  const std::vector<double> elev = {10};
  write_shapefile(path("roofz"), SHPT_ARCZ, {Shape{{0}, {20, 21}, {0, 0}, {7, 8}}}, &elev);
  write_shapefile(path("flat"), SHPT_ARC, {Shape{{0}, {0, 1}, {0, 0}, {}}}, &elev);
  EXPECT_TRUE(shapefile_has_z(path("roofz.shp")));
  EXPECT_FALSE(shapefile_has_z(path("flat.shp")));
  InputSet in;
  const std::vector<InputPart> parts =
      read_inputs({parse_input_spec(path("roofz.shp")), parse_input_spec(path("flat.shp"))}, ReadOptions{}, in);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_TRUE(parts[0].z_complete);
  EXPECT_FALSE(parts[1].z_complete);
  const DrapeStats stats = apply_z_rules(in, parts);
  EXPECT_EQ(stats.zero_z, (std::vector<uint64_t>{0, 2}));
  EXPECT_EQ(in.lines[0].points[1].z, 8.0);
  InputSet field;
  const std::vector<InputPart> under_field =
      read_inputs({parse_input_spec(path("roofz.shp"))}, ReadOptions{.z_field = "ELEV"}, field);
  EXPECT_FALSE(under_field.at(0).z_complete);
  EXPECT_EQ(field.lines[0].points[1].z, 10.0);
}

TEST_F(Shapefile, MissingZFieldListsTheFields) {
  const std::vector<double> elev = {10, 20};
  write_shapefile(path("flat"), SHPT_ARC, {Shape{{0}, {0, 1}, {0, 0}, {}}, Shape{{0}, {0, 1}, {1, 1}, {}}},
                  &elev);
  InputSet in;
  expect_input_error([&] { read_input(path("flat.shp"), {.z_field = "HEIGHT"}, in); },
                     "no field HEIGHT in " + path("flat.dbf") + " (fields: ID, ELEV)", 0);
  read_input(path("flat.shp"), {.z_field = "ELEV"}, in);
  EXPECT_EQ(in.lines[1].points, (Points{{0, 1, 20}, {1, 1, 20}}));
  fs::remove(path("flat.dbf"));
  expect_input_error([&] { read_input(path("flat.shp"), {.z_field = "ELEV"}, in); }, "no attribute file", 0);
  InputSet plain;
  read_input(path("flat.shp"), {}, plain);  // without --z-field the .dbf is not needed: z = 0
  EXPECT_EQ(plain.lines[0].points[0], (Point3{0, 0, 0}));
}

TEST_F(Shapefile, PolygonZWithHole) {
  // Outer ring closed with a repeated vertex; the hole written without its closing vertex.
  write_shapefile(path("roofs"), SHPT_POLYGONZ,
                  {Shape{{0, 6},
                         {0, 0, 10, 10, 10, 0, 2, 4, 4},
                         {0, 10, 10, 10, 0, 0, 2, 2, 4},
                         {5, 5, 5, 5, 5, 5, 6, 6, 6}}});
  InputSet in;
  read_input(path("roofs.shp"), {}, in);
  ASSERT_EQ(in.lines.size(), 2u);
  EXPECT_TRUE(in.lines[0].closed);
  EXPECT_TRUE(in.lines[1].closed);
  EXPECT_EQ(in.lines[0].points, (Points{{0, 0, 5}, {0, 10, 5}, {10, 10, 5}, {10, 0, 5}}));
  EXPECT_EQ(in.lines[1].points, (Points{{2, 2, 6}, {4, 2, 6}, {4, 4, 6}}));
  EXPECT_EQ(in.lines[1].record, 1u);
  EXPECT_EQ(in.repairs.repeated_vertices, 1u);
  EXPECT_EQ(in.repairs.rings_closed, 1u);
}

TEST_F(Shapefile, TruncatedShp) {
  write_contours(path("c"));
  std::string shp = read_bytes(path("c.shp"));
  write_bytes(path("c.shp"), shp.substr(0, shp.size() - 16));
  InputSet in;
  expect_input_error([&] { read_input(path("c.shp"), {}, in); }, "c.shp: truncated: the header gives", 0);
  // The same cut with the header's length patched to match: the damage shows at record 2.
  shp.resize(shp.size() - 16);
  const uint32_t words = uint32_t(shp.size() / 2);
  for (int k = 0; k < 4; ++k) shp[24 + k] = char((words >> (24 - 8 * k)) & 0xff);
  write_bytes(path("c.shp"), shp);
  expect_input_error([&] { read_input(path("c.shp"), {}, in); }, "c.shp:2: corrupt or unreadable record", 2);
  write_bytes(path("c.shp"), shp.substr(0, 60));
  expect_input_error([&] { read_input(path("c.shp"), {}, in); }, "shorter than the 100-byte header", 0);
}

TEST_F(Shapefile, TruncatedShxAndMissingShx) {
  write_contours(path("c"));
  const std::string shx = read_bytes(path("c.shx"));
  write_bytes(path("c.shx"), shx.substr(0, shx.size() - 8));
  InputSet in;
  expect_input_error([&] { read_input(path("c.shp"), {}, in); }, "c.shx: truncated", 0);
  fs::remove(path("c.shx"));
  expect_input_error([&] { read_input(path("c.shp"), {}, in); }, "no index file", 0);
}

TEST_F(Shapefile, CorruptDbf) {
  write_contours(path("c"));
  const std::string dbf = read_bytes(path("c.dbf"));
  InputSet in;
  // A value that is not a number, in record 2.
  std::string bad = dbf;
  const size_t at = bad.find("200.250");
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, 7, "2x0.250");
  write_bytes(path("c.dbf"), bad);
  expect_input_error([&] { read_input(path("c.shp"), {.z_field = "ELEV"}, in); },
                     "c.dbf:2: z field is not a number", 2);
  // Records cut off.
  write_bytes(path("c.dbf"), dbf.substr(0, dbf.size() - 20));
  expect_input_error([&] { read_input(path("c.shp"), {.z_field = "ELEV"}, in); },
                     "c.dbf: truncated or corrupt", 0);
  // Not a DBF at all.
  write_bytes(path("c.dbf"), "garbage");
  expect_input_error([&] { read_input(path("c.shp"), {.z_field = "ELEV"}, in); },
                     "c.dbf: cannot read the attribute table: not a valid .dbf file", 0);
}

TEST_F(Shapefile, MeasuredTypesHaveNoZAndMultiPatchIsRefused) {
  write_shapefile(path("m"), SHPT_POLYGONM, {Shape{{0}, {0, 1, 1, 0}, {0, 0, 1, 0}, {}}});
  write_shapefile(path("mpz"), SHPT_MULTIPOINTZ, {Shape{{}, {1, 2}, {3, 4}, {5, 6}}});
  InputSet in;
  read_input(path("m.shp"), {}, in);
  read_input(path("mpz.shp"), {}, in);
  ASSERT_EQ(in.lines.size(), 1u);
  EXPECT_EQ(in.lines[0].points, (Points{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
  EXPECT_EQ(in.points, (Points{{1, 3, 5}, {2, 4, 6}}));
  write_shapefile(path("patch"), SHPT_MULTIPATCH, {Shape{{0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}}});
  expect_input_error([&] { read_input(path("patch.shp"), {}, in); }, "shape type MultiPatch is not supported",
                     0);
}

TEST_F(Shapefile, NonFiniteCoordinateNamesTheRecord) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  write_shapefile(path("p"), SHPT_POINT, {Shape{{}, {1}, {1}, {}}, Shape{{}, {nan}, {2}, {}}});
  InputSet in;
  expect_input_error([&] { read_input(path("p.shp"), {}, in); }, "p.shp:2: coordinate is not a finite number",
                     2);
}

TEST_F(Shapefile, EmptyShapefileIsNoGeometry) {
  write_shapefile(path("none"), SHPT_ARC, {});
  write_shapefile(path("nulls"), SHPT_ARC, {Shape{{}, {}, {}, {}, true}});
  InputSet in;
  expect_input_error([&] { read_input(path("none.shp"), {}, in); }, "no geometry", 0);
  expect_input_error([&] { read_input(path("nulls.shp"), {}, in); }, "no geometry", 0);
}
