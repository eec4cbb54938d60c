// The GeoJSON reader: every geometry type gives what the same geometry gives as WKT; z from a feature
// property; the legacy crs member; bad input named by feature. Through the CLI: the mesh of a GeoJSON file is
// the mesh of the same geometry as WKT, byte for byte, also when GDAL's ogr2ogr (an independent writer) made
// the GeoJSON.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "io/input_spec.hpp"
#include "io/read_geojson.hpp"
#include "io/readers.hpp"

using namespace cdtgpu;
namespace fs = std::filesystem;

namespace {

InputSet geojson(const std::string& text, const std::string& z_property = "") {
  InputSet in;
  in.nan_for_missing_z = true;
  read_geojson_text(text, "t.geojson", z_property, in);
  return in;
}

InputSet wkt(const std::string& text) {
  InputSet in;
  in.nan_for_missing_z = true;
  read_wkt_text(text, "t.wkt", in);
  return in;
}

// Bit for bit: a z read as missing is a NaN, which == would call different.
bool same(const Point3& a, const Point3& b) {
  return std::bit_cast<uint64_t>(a.x) == std::bit_cast<uint64_t>(b.x) &&
         std::bit_cast<uint64_t>(a.y) == std::bit_cast<uint64_t>(b.y) &&
         std::bit_cast<uint64_t>(a.z) == std::bit_cast<uint64_t>(b.z);
}

void expect_same_geometry(const InputSet& a, const InputSet& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) EXPECT_TRUE(same(a.points[i], b.points[i])) << "point " << i;
  ASSERT_EQ(a.lines.size(), b.lines.size());
  for (size_t i = 0; i < a.lines.size(); ++i) {
    EXPECT_EQ(a.lines[i].closed, b.lines[i].closed) << "line " << i;
    ASSERT_EQ(a.lines[i].points.size(), b.lines[i].points.size()) << "line " << i;
    for (size_t k = 0; k < a.lines[i].points.size(); ++k)
      EXPECT_TRUE(same(a.lines[i].points[k], b.lines[i].points[k])) << "line " << i << " vertex " << k;
  }
  EXPECT_EQ(a.repairs.repeated_vertices, b.repairs.repeated_vertices);
  EXPECT_EQ(a.repairs.rings_closed, b.repairs.rings_closed);
  EXPECT_EQ(a.repairs.degenerate_lines, b.repairs.degenerate_lines);
}

void expect_error(const std::string& text, const std::string& part, const std::string& z_property = "") {
  try {
    geojson(text, z_property);
    ADD_FAILURE() << "no InputError; expected one containing '" << part << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("t.geojson: ", 0), 0u) << e.what();
  }
}

std::string feature(const std::string& geometry, const std::string& properties = "null") {
  return R"({"type": "Feature", "properties": )" + properties + R"(, "geometry": )" + geometry + "}";
}

std::string collection(const std::vector<std::string>& features) {
  std::string s = R"({"type": "FeatureCollection", "features": [)";
  for (size_t i = 0; i < features.size(); ++i) s += (i ? ",\n" : "\n") + features[i];
  return s + "]}";
}

// Each geometry type, 2D and with z, bare, as a Feature and in a FeatureCollection, against the same WKT.
TEST(GeoJson, EveryGeometryTypeIsItsWkt) {
  const std::pair<std::string, std::string> cases[] = {
      {R"({"type": "Point", "coordinates": [151.2, -33.9]})", "POINT (151.2 -33.9)"},
      {R"({"type": "Point", "coordinates": [151.2, -33.9, 12.5]})", "POINT Z (151.2 -33.9 12.5)"},
      {R"({"type": "MultiPoint", "coordinates": [[151, -33], [151.5, -33.5, 3]]})",
       "MULTIPOINT ((151 -33), (151.5 -33.5))"},  // replaced below: mixed dimensions
      {R"({"type": "LineString", "coordinates": [[151, -33, 1], [151.1, -33, 2], [151.1, -33, 2], [151.2, -33.1, 3]]})",
       "LINESTRING Z (151 -33 1, 151.1 -33 2, 151.1 -33 2, 151.2 -33.1 3)"},
      {R"({"type": "MultiLineString", "coordinates": [[[151, -33], [151.1, -33]], [[151, -33.2], [151.3, -33.3]]]})",
       "MULTILINESTRING ((151 -33, 151.1 -33), (151 -33.2, 151.3 -33.3))"},
      {R"({"type": "Polygon", "coordinates": [[[151, -33, 5], [151.1, -33, 5], [151.1, -33.1, 5], [151, -33, 5]],
           [[151.05, -33.02, 6], [151.06, -33.02, 6], [151.06, -33.03, 6], [151.05, -33.02, 6]]]})",
       "POLYGON Z ((151 -33 5, 151.1 -33 5, 151.1 -33.1 5, 151 -33 5), "
       "(151.05 -33.02 6, 151.06 -33.02 6, 151.06 -33.03 6, 151.05 -33.02 6))"},
      {R"({"type": "MultiPolygon", "coordinates": [[[[151, -33], [151.1, -33], [151.1, -33.1], [151, -33]]],
           [[[152, -33], [152.1, -33], [152.1, -33.1], [152.05, -33.2]]]]})",
       "MULTIPOLYGON (((151 -33, 151.1 -33, 151.1 -33.1, 151 -33)), ((152 -33, 152.1 -33, 152.1 -33.1, 152.05 -33.2)))"},
      {R"({"type": "GeometryCollection", "geometries": [{"type": "Point", "coordinates": [150, -30, 1]},
           {"type": "GeometryCollection", "geometries": [{"type": "LineString", "coordinates": [[150, -30, 2], [150.5, -30.5, 3]]}]}]})",
       "GEOMETRYCOLLECTION (POINT Z (150 -30 1), GEOMETRYCOLLECTION (LINESTRING Z (150 -30 2, 150.5 -30.5 3)))"},
  };
  for (const auto& [json, text] : cases) {
    SCOPED_TRACE(json);
    const InputSet g = geojson(json);
    InputSet w = wkt(text);
    if (text.rfind("MULTIPOINT", 0) == 0) w.points[1].z = 3;  // WKT has no mixed dimensions; GeoJSON may
    expect_same_geometry(g, w);
    expect_same_geometry(geojson(feature(json)), w);
    expect_same_geometry(geojson(collection({feature(json)})), w);
  }
  // All of them in one collection, with null and empty geometries (counted as NULL shapes), is their WKT in order.
  std::vector<std::string> features;
  std::string all;
  for (const auto& [json, text] : cases) {
    if (text.rfind("MULTIPOINT", 0) == 0) continue;
    features.push_back(feature(json, R"({"name": "x"})"));
    all += text + "\n";
  }
  features.push_back(feature("null"));
  features.push_back(feature(R"({"type": "LineString", "coordinates": []})"));
  const InputSet g = geojson(collection(features));
  expect_same_geometry(g, wkt(all));
  EXPECT_EQ(g.repairs.null_shapes, 2u);
  EXPECT_EQ(g.repairs.repeated_vertices, 1u);
  EXPECT_EQ(g.repairs.rings_closed, 1u);  // the MultiPolygon's second ring, not closed
}

TEST(GeoJson, ZFromAFeatureProperty) {
  const std::string text = collection({
      feature(R"({"type": "LineString", "coordinates": [[151, -33, 99], [151.1, -33]]})", R"({"ELEV": 120.5})"),
      feature(R"({"type": "Polygon", "coordinates": [[[151, -33], [151.1, -33], [151.1, -33.1], [151, -33]]]})",
              R"({"id": 2, "elev": "130"})"),  // another case; a number as text (CSV conversions)
      feature("null"),                          // no geometry: no z needed
  });
  const InputSet in = geojson(text, "ELEV");
  expect_same_geometry(in, wkt("LINESTRING Z (151 -33 120.5, 151.1 -33 120.5)\n"
                               "POLYGON Z ((151 -33 130, 151.1 -33 130, 151.1 -33.1 130, 151 -33 130))"));
  EXPECT_EQ(in.lines[1].record, 2u);  // the feature number
  expect_error(collection({feature(R"({"type": "Point", "coordinates": [1, 2]})", R"({"id": 1, "name": "a"})")}),
               "feature 1: no property ELEV for z (properties: id, name)", "ELEV");
  expect_error(collection({feature(R"({"type": "Point", "coordinates": [1, 2]})", R"({"ELEV": "high"})")}),
               "feature 1: property ELEV is 'high', not a number", "ELEV");
  expect_error(collection({feature(R"({"type": "Point", "coordinates": [1, 2]})", R"({"ELEV": null})")}),
               "property ELEV is null, not a number", "ELEV");
  expect_error(R"({"type": "Point", "coordinates": [1, 2]})", "bare Point without properties", "ELEV");
}

// The file the fuzz seeds start from: every type, a crs member, z from the property "z" for every feature.
TEST(GeoJson, ReadersSampleFile) {
  InputSet in;
  read_input(std::string(CDTGPU_SOURCE_DIR) + "/tests/data/readers/features.geojson", {}, in);
  EXPECT_EQ(in.points.size(), 4u);
  EXPECT_EQ(in.lines.size(), 6u);
  EXPECT_EQ(in.repairs.null_shapes, 1u);
  EXPECT_NE(in.source_crs_wkt.find("GDA2020_MGA_Zone_56"), std::string::npos);
  InputSet z;
  read_geojson_text(R"({"type": "Feature", "properties": {"z": 5}, "geometry": {"type": "Point", "coordinates": [151, -33, 1]}})",
                    "t.geojson", "z", z);
  EXPECT_EQ(z.points.at(0).z, 5);  // the property wins over the position's z, as a shapefile's field does
}

// The CLI's per-input z=NAME reaches the reader; --z-field stays a shapefile option.
TEST(GeoJson, ZPropertyIsAPerInputOption) {
  const InputSpec s = parse_input_spec("contours.geojson:z=ELEV,role=breakline");
  EXPECT_EQ(s.path, "contours.geojson");
  EXPECT_EQ(s.z_field, "ELEV");
}

TEST(GeoJson, LegacyCrsMember) {
  auto with_crs = [](const std::string& name, const std::string& coordinates) {
    return R"({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": ")" + name +
           R"("}}, "features": [)" + feature(R"({"type": "MultiPoint", "coordinates": )" + coordinates + "}") +
           "]}";
  };
  const std::string mga = "[[334000, 6250000, 1], [334100, 6250100, 2], [334000, 6250200, 3]]";
  const std::string lon_lat = "[[151.2, -33.9, 1], [151.21, -33.9, 2], [151.2, -33.91, 3]]";
  for (const char* name : {"urn:ogc:def:crs:EPSG::7856", "EPSG:7856", "http://www.opengis.net/def/crs/EPSG/0/7856"}) {
    const InputSet in = geojson(with_crs(name, mga));
    EXPECT_NE(in.source_crs_wkt.find("GDA2020_MGA_Zone_56"), std::string::npos) << name;
    const Crs crs = choose_crs(in, {});
    EXPECT_FALSE(crs.from_geographic);
    EXPECT_EQ(crs.epsg, 7856) << name;
  }
  // {"type": "EPSG", "properties": {"code": 28355}} (GeoJSON before 2008's final text).
  InputSet in = geojson(R"({"type": "MultiPoint", "crs": {"type": "EPSG", "properties": {"code": 28355}}, "coordinates": )" +
                        mga + "}");
  EXPECT_EQ(choose_crs(in, {}).epsg, 28355);
  // Geographic: CRS84 and no crs are WGS 84 (UTM), GDA94 / GDA2020 codes go to their MGA zone.
  EXPECT_EQ(choose_crs(geojson(with_crs("urn:ogc:def:crs:OGC:1.3:CRS84", lon_lat)), {}).epsg, 32756);
  EXPECT_EQ(choose_crs(geojson(R"({"type": "MultiPoint", "coordinates": )" + lon_lat + "}"), {}).epsg, 32756);
  EXPECT_EQ(choose_crs(geojson(with_crs("urn:ogc:def:crs:EPSG::4283", lon_lat)), {}).epsg, 28356);
  EXPECT_EQ(choose_crs(geojson(with_crs("urn:ogc:def:crs:EPSG::7844", lon_lat)), {}).epsg, 7856);
  // Outside lon/lat under a geographic crs member: named by feature and position.
  expect_error(with_crs("urn:ogc:def:crs:OGC:1.3:CRS84", mga),
               "feature 1: MultiPoint point 1: (334000 6250000) is not a longitude/latitude, and the \"crs\" member "
               "names the geographic EPSG:4326");
  // Projected coordinates without a crs member (GDAL's GeoJSON of a layer without a CRS): kept as read, no CRS.
  in = geojson(R"({"type": "MultiPoint", "coordinates": )" + mga + "}");
  EXPECT_EQ(in.source_crs_wkt, "");
  EXPECT_FALSE(choose_crs(in, {}).from_geographic);
  // A code cdtgpu does not know: kept as read when projected, refused when it could be lon/lat on any datum.
  in = geojson(with_crs("urn:ogc:def:crs:EPSG::2193", mga));
  EXPECT_EQ(in.source_crs_wkt, "");
  EXPECT_EQ(in.points.size(), 3u);
  expect_error(with_crs("urn:ogc:def:crs:EPSG::4269", lon_lat), "EPSG:4269, which cdtgpu does not know");
  expect_error(with_crs("WGS84", lon_lat), "not an EPSG code");
  expect_error(R"({"type": "Point", "crs": {"type": "link", "properties": {}}, "coordinates": [1, 2]})",
               "of type \"link\" is not supported");
}

TEST(GeoJson, BadInputNamesTheFeature) {
  expect_error("{\"type\": \"Point\",\n \"coordinates\": [1, 2,]}", "not valid JSON: parse error at line 2, column 23");
  expect_error(R"({"type": "Point", "coordinates": [1e400, 2]})", "not valid JSON: number overflow");
  expect_error("[1, 2]", "not GeoJSON: the top level is an array");
  expect_error(R"({"features": []})", "the top-level object has no \"type\"");
  expect_error(R"({"type": "FeatureCollection", "features": {}})", "no \"features\" array");
  const std::string ok = feature(R"({"type": "Point", "coordinates": [1, 2]})");
  auto second = [&](const std::string& f) { return collection({ok, f}); };
  expect_error(second(R"({"type": "Point", "coordinates": [1, 2]})"), "feature 2: expected a Feature, found a Point");
  expect_error(second(feature(R"({"type": "Curve", "coordinates": [1, 2]})")), "feature 2: unknown geometry type 'Curve'");
  expect_error(second(feature(R"({"type": "Point", "coordinates": [1, "2"]})")), "feature 2: Point: number 2 is a string");
  expect_error(second(feature(R"({"type": "Point", "coordinates": [1]})")),
               "feature 2: Point: a position needs at least 2 numbers, found 1");
  expect_error(second(feature(R"({"type": "LineString", "coordinates": [[1, 2]]})")),
               "feature 2: LineString: a LineString needs at least 2 positions, found 1");
  expect_error(second(feature(R"({"type": "MultiPolygon", "coordinates": [[[[1, 2], [1, 3], [1, 2]]]]})")),
               "feature 2: MultiPolygon polygon 1, ring 1: a linear ring needs at least 4 positions, found 3");
  expect_error(second(feature(R"({"type": "MultiLineString", "coordinates": [[[1, 2], [3, 4]], [[1, 2], 7]]})")),
               "feature 2: MultiLineString line 2, position 2: expected a position (an array of numbers), found a number");
  expect_error(second(feature(R"({"type": "Polygon"})")), "feature 2: Polygon has no \"coordinates\"");
  expect_error(second(R"({"type": "Feature", "properties": {}})"), "feature 2: the Feature has no \"geometry\"");
  expect_error(second(R"({"type": "Feature", "properties": 3, "geometry": null})"),
               "feature 2: \"properties\" is a number");
  expect_error(R"({"type": "Point", "crs": {"type": "name", "properties": {"name": "EPSG:4283"}}, "coordinates": [1, 95]})",
               "feature 1: Point: (1 95) is not a longitude/latitude");
  std::string deep = R"({"type": "Point", "coordinates": [1, 2]})";
  for (int i = 0; i < 40; ++i) deep = R"({"type": "GeometryCollection", "geometries": [)" + deep + "]}";
  expect_error(deep, "nested too deeply");
  expect_error(collection({feature("null")}), "no geometry");
}

// Through the CLI, against WKT; with ogr2ogr (GDAL), when installed, as an independent writer of the GeoJSON.
class GeoJsonCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("geojson_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
  static std::string slurp(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
  int run(const std::string& command) const {
    const int status = std::system((command + " >" + path("out.txt") + " 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string cdtgpu() const { return CDTGPU_BINARY; }
  // DEM points around the lines below, in projected metres.
  void write_dem() const {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0, 1);
    std::ostringstream s;
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 20; ++j)
        s << 334000 + i * 10 + int(u(rng) * 100) / 100.0 << ' ' << 6250000 + j * 10 + int(u(rng) * 100) / 100.0
          << ' ' << 100 + i + j * 0.5 << '\n';
    write("dem.xyz", s.str());
  }
  fs::path dir_;
};

const char* kLinesWkt =
    "LINESTRING Z (334005 6250005 110, 334100 6250050 111, 334185 6250180 112)\n"
    "MULTILINESTRING Z ((334020 6250150 105, 334060 6250120 106), (334010 6250100 104, 334030 6250090 104))\n"
    "POLYGON Z ((334120 6250020 130, 334140 6250020 130, 334140 6250040 130, 334120 6250040 130, 334120 6250020 130))\n"
    "MULTIPOLYGON Z (((334150 6250100 140, 334170 6250100 140, 334170 6250120 140, 334150 6250100 140)))\n"
    "POINT Z (334077 6250077 120)\n"
    "MULTIPOINT Z ((334033 6250033 101), (334166 6250166 150))\n";

TEST_F(GeoJsonCli, MeshOfGeoJsonIsTheMeshOfTheSameWkt) {
  write_dem();
  write("lines.wkt", kLinesWkt);
  write("lines.geojson", collection({
      feature(R"({"type": "LineString", "coordinates": [[334005, 6250005, 110], [334100, 6250050, 111], [334185, 6250180, 112]]})"),
      feature(R"({"type": "MultiLineString", "coordinates": [[[334020, 6250150, 105], [334060, 6250120, 106]], [[334010, 6250100, 104], [334030, 6250090, 104]]]})"),
      feature(R"({"type": "Polygon", "coordinates": [[[334120, 6250020, 130], [334140, 6250020, 130], [334140, 6250040, 130], [334120, 6250040, 130], [334120, 6250020, 130]]]})"),
      feature(R"({"type": "MultiPolygon", "coordinates": [[[[334150, 6250100, 140], [334170, 6250100, 140], [334170, 6250120, 140], [334150, 6250100, 140]]]]})"),
      feature(R"({"type": "Point", "coordinates": [334077, 6250077, 120]})"),
      feature(R"({"type": "MultiPoint", "coordinates": [[334033, 6250033, 101], [334166, 6250166, 150]]})"),
  }).insert(1, R"("crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::7856"}}, )"));
  ASSERT_EQ(run(cdtgpu() + " triangulate " + path("dem.xyz") + " " + path("lines.wkt") + " -o " + path("w.wkt")), 0)
      << slurp(path("out.txt"));
  ASSERT_EQ(run(cdtgpu() + " triangulate " + path("dem.xyz") + " " + path("lines.geojson") + " -o " + path("g.wkt") +
                " --stats " + path("s.json")),
            0)
      << slurp(path("out.txt"));
  EXPECT_EQ(slurp(path("g.wkt")), slurp(path("w.wkt")));
  EXPECT_NE(slurp(path("g.prj")).find("GDA2020_MGA_Zone_56"), std::string::npos);  // the crs member's CRS
  EXPECT_NE(slurp(path("s.json")).find("\"crs_epsg\": 7856"), std::string::npos);
}

TEST_F(GeoJsonCli, GeoJsonWrittenByOgr2ogrReadsAsItsWkt) {
  if (std::system("ogr2ogr --version >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "ogr2ogr (Debian gdal-bin) is not installed: the GeoJSON of an independent writer is not tested";
  write_dem();
  std::string csv = "WKT,ELEV\n";
  std::istringstream lines(kLinesWkt);
  for (std::string line; std::getline(lines, line);) csv += "\"" + line + "\",7\n";
  write("lines.csv", csv);
  write("lines.wkt", kLinesWkt);
  ASSERT_EQ(run("ogr2ogr -f GeoJSON -a_srs EPSG:7856 " + path("ogr.geojson") + " " + path("lines.csv")), 0)
      << slurp(path("out.txt"));
  ASSERT_EQ(run(cdtgpu() + " triangulate " + path("dem.xyz") + " " + path("lines.wkt") + " -o " + path("w.wkt")), 0)
      << slurp(path("out.txt"));
  ASSERT_EQ(run(cdtgpu() + " triangulate " + path("dem.xyz") + " " + path("ogr.geojson") + " -o " + path("g.wkt")), 0)
      << slurp(path("out.txt"));
  EXPECT_EQ(slurp(path("g.wkt")), slurp(path("w.wkt")));
  EXPECT_NE(slurp(path("g.prj")).find("GDA2020_MGA_Zone_56"), std::string::npos);
  // z from the ELEV property (a string in GDAL's CSV import): every line and ring at 7.
  ASSERT_EQ(run(cdtgpu() + " triangulate " + path("ogr.geojson") + ":z=ELEV -o " + path("z.wkt")), 0)
      << slurp(path("out.txt"));
  const std::string z = slurp(path("z.wkt"));
  EXPECT_NE(z.find(" 7,"), std::string::npos);
  EXPECT_EQ(z.find(" 110,"), std::string::npos);
}

// cdtgpu's own --contours-out GeoJSON reads back as the same lines as its WKT, with and without a known CRS.
TEST_F(GeoJsonCli, ContoursWrittenAsGeoJsonReadBackAsTheirWkt) {
  write_dem();
  // The DEM as a GeoJSON MultiPoint naming GDA2020 / MGA zone 56: the contours' GeoJSON names it too.
  std::string dem = R"({"type": "MultiPoint", "crs": {"type": "name", "properties": {"name": "EPSG:7856"}}, )"
                    R"("coordinates": [)";
  std::istringstream xyz(slurp(path("dem.xyz")));
  double x, y, z;
  for (int i = 0; xyz >> x >> y >> z; ++i) dem += (i ? ", [" : "[") + number_text(x) + ", " + number_text(y) + ", " + number_text(z) + "]";
  write("dem.geojson", dem + "]}");
  for (const std::string crs : {"", "EPSG:7856"}) {
    SCOPED_TRACE(crs);
    const std::string contours = cdtgpu() + " triangulate " + path(crs.empty() ? "dem.xyz" : "dem.geojson") +
                                 " -o " + path("tin.ply") + " --interval 2 --contours-out ";
    ASSERT_EQ(run(contours + path("c.geojson")), 0) << slurp(path("out.txt"));
    ASSERT_EQ(run(contours + path("c.wkt")), 0) << slurp(path("out.txt"));
    EXPECT_EQ(slurp(path("c.geojson")).find("\"crs\"") != std::string::npos, !crs.empty());
    ASSERT_EQ(run(cdtgpu() + " triangulate " + path("c.geojson") + " -o " + path("g.wkt")), 0) << slurp(path("out.txt"));
    ASSERT_EQ(run(cdtgpu() + " triangulate " + path("c.wkt") + " -o " + path("w.wkt")), 0) << slurp(path("out.txt"));
    EXPECT_GT(slurp(path("g.wkt")).size(), 1000u);
    EXPECT_EQ(slurp(path("g.wkt")), slurp(path("w.wkt")));
  }
}

TEST_F(GeoJsonCli, BadGeoJsonExitsTwoNamingTheFeature) {
  write("bad.geojson", collection({feature(R"({"type": "Point", "coordinates": [151, -33]})"),
                                   feature(R"({"type": "Point", "coordinates": [151, -33, "x"]})")}));
  EXPECT_EQ(run(cdtgpu() + " triangulate " + path("bad.geojson") + " -o " + path("b.ply")), 2);
  EXPECT_NE(slurp(path("out.txt")).find("bad.geojson: feature 2: Point: number 3 is a string"), std::string::npos)
      << slurp(path("out.txt"));
  EXPECT_FALSE(fs::exists(path("b.ply")));
  write("p.xyz", "0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(run(cdtgpu() + " triangulate " + path("p.xyz") + ":z=ELEV -o " + path("b.ply")), 2);
  EXPECT_NE(slurp(path("out.txt")).find("only shapefiles and GeoJSON have"), std::string::npos) << slurp(path("out.txt"));
}

}  // namespace
