// LandXML and 2DM meshes: exact text of a small mesh, the northing-easting order of LandXML points, a
// well-formed document (xmllint, when installed), a LandXML point list read back by a reader written here
// (not the library's), bit-exact round trips through read_mesh_file, the CRS in the file and the .prj beside
// it, whole-or-nothing files, and errors naming the file and line.
#include "io/mesh_formats.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cfloat>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "io/writers.hpp"

namespace cdtgpu {
namespace {

namespace fs = std::filesystem;

class MeshFormatsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ =
        fs::temp_directory_path() / ("cdtgpu_meshformats_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void expect_identical(const Mesh& a, const Mesh& b, const std::string& what) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
  for (size_t i = 0; i < a.vertices.size(); ++i)
    EXPECT_EQ(std::memcmp(&a.vertices[i], &b.vertices[i], sizeof(Point3)), 0) << what << ": vertex " << i;
  EXPECT_EQ(a.triangles, b.triangles) << what;
}

Mesh small_mesh() {
  Mesh m;
  m.vertices = {
      {500000, 6000000, 10.5}, {500010, 6000000, 11}, {500000.25, 6000010, 12}, {500010, 6000010, -0.1}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  return m;
}

Mesh awkward_mesh() {
  Mesh m;
  m.vertices = {
      {-DBL_MAX, 0.1, -0.0},
      {-0.0, 1e-300, 4.9406564584124654e-324},
      {0.1, 6123456.789, 9007199254740994.0},
      {1.0 / 3, -2.2250738585072014e-308, 0.1 + 0.2},
      {6123456.789, 1e22, 123456789012345678.0},
      {9007199254740996.0, -0.1, DBL_MAX},
  };
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
  return m;
}

Mesh random_mesh(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Mesh m;
  for (size_t i = 0; i < n; ++i) {
    double d[3];
    for (double& v : d) do
        v = std::bit_cast<double>(rng());
      while (!std::isfinite(v));
    if (i % 2)
      m.vertices.push_back({d[0], d[1], d[2]});
    else
      m.vertices.push_back({double(rng() % 1000000000) / 1000, double(rng() % 7000000000) / 1000, 1.5});
  }
  for (uint32_t i = 0; i + 2 < n; ++i) m.triangles.push_back({i, i + 2, i + 1});
  return m;
}

Crs mga56() {
  InputSet in;
  in.points = {{151.3, -33.7, 0}};
  return choose_crs(in, parse_crs("EPSG:7856"));
}

std::string landxml_text(const Mesh& m, const Crs& crs, std::time_t stamp = 0) {
  std::ostringstream out;
  write_landxml(m, crs, stamp, out);
  return out.str();
}

// A reader of our own for the test: every <P id="..">a b c</P> and <F>i j k</F>, by regular expression.
struct Parsed {
  std::vector<uint64_t> ids;
  std::vector<std::array<double, 3>> pnts;  // as written: northing easting elevation
  std::vector<std::array<uint64_t, 3>> faces;
};
Parsed parse_by_regex(const std::string& xml) {
  Parsed p;
  const std::regex pr(R"re(<P id="(\d+)">(\S+) (\S+) (\S+)</P>)re"), fr(R"re(<F>(\d+) (\d+) (\d+)</F>)re");
  auto num = [](const std::string& s) {
    double v = 0;
    std::from_chars(s.data(), s.data() + s.size(), v);
    return v;
  };
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), pr); it != std::sregex_iterator(); ++it) {
    p.ids.push_back(std::stoull((*it)[1]));
    p.pnts.push_back({num((*it)[2]), num((*it)[3]), num((*it)[4])});
  }
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), fr); it != std::sregex_iterator(); ++it)
    p.faces.push_back({std::stoull((*it)[1]), std::stoull((*it)[2]), std::stoull((*it)[3])});
  return p;
}

bool have_xmllint() { return std::system("command -v xmllint >/dev/null 2>&1") == 0; }

TEST_F(MeshFormatsTest, LandXmlTextIsExact) {
  Crs crs;
  crs.name = "none";
  EXPECT_EQ(landxml_text(small_mesh(), crs, 86400 + 3661),
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<LandXML xmlns=\"http://www.landxml.org/schema/LandXML-1.2\" "
            "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
            "xsi:schemaLocation=\"http://www.landxml.org/schema/LandXML-1.2 "
            "http://www.landxml.org/schema/LandXML-1.2/LandXML-1.2.xsd\" version=\"1.2\" date=\"1970-01-02\" "
            "time=\"01:01:01\">\n"
            "  <Units>\n    <Metric areaUnit=\"squareMeter\" linearUnit=\"meter\" volumeUnit=\"cubicMeter\" "
            "temperatureUnit=\"celsius\" pressureUnit=\"milliBars\" angularUnit=\"decimal degrees\" "
            "directionUnit=\"decimal degrees\"/>\n  </Units>\n"
            "  <Application name=\"cdtgpu\" version=\"0.1.0\"/>\n"
            "  <Surfaces>\n    <Surface name=\"TIN\">\n      <Definition surfType=\"TIN\">\n        <Pnts>\n"
            "          <P id=\"1\">6000000 500000 10.5</P>\n"
            "          <P id=\"2\">6000000 500010 11</P>\n"
            "          <P id=\"3\">6000010 500000.25 12</P>\n"
            "          <P id=\"4\">6000010 500010 -0.1</P>\n"
            "        </Pnts>\n        <Faces>\n"
            "          <F>1 2 3</F>\n"
            "          <F>2 4 3</F>\n"
            "        </Faces>\n      </Definition>\n    </Surface>\n  </Surfaces>\n</LandXML>\n");
}

TEST_F(MeshFormatsTest, LandXmlPointsAreNorthingEastingElevationWithOneBasedIds) {
  const Mesh m = random_mesh(500, 3);
  const Parsed p = parse_by_regex(landxml_text(m, Crs{}));
  ASSERT_EQ(p.pnts.size(), m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    EXPECT_EQ(p.ids[i], i + 1);
    EXPECT_EQ(std::bit_cast<uint64_t>(p.pnts[i][0]), std::bit_cast<uint64_t>(m.vertices[i].y)) << i;
    EXPECT_EQ(std::bit_cast<uint64_t>(p.pnts[i][1]), std::bit_cast<uint64_t>(m.vertices[i].x)) << i;
    EXPECT_EQ(std::bit_cast<uint64_t>(p.pnts[i][2]), std::bit_cast<uint64_t>(m.vertices[i].z)) << i;
  }
  ASSERT_EQ(p.faces.size(), m.triangles.size());
  for (size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(p.faces[t][k], m.triangles[t][k] + 1u);
}

TEST_F(MeshFormatsTest, LandXmlRecordsTheEpsgCodeAndEscapesTheWkt) {
  const Crs crs = mga56();
  ASSERT_EQ(crs.epsg, 7856);
  const std::string xml = landxml_text(small_mesh(), crs);
  EXPECT_NE(
      xml.find(
          "<CoordinateSystem name=\"GDA2020 / MGA zone 56\" epsgCode=\"7856\" ogcWktCode=\"PROJCS[&quot;"),
      std::string::npos)
      << xml.substr(0, 1500);
  Crs odd;
  odd.projected = true;
  odd.name = "a<b & \"c\"\nd";
  EXPECT_NE(landxml_text(small_mesh(), odd).find("name=\"a&lt;b &amp; &quot;c&quot;&#10;d\""),
            std::string::npos);
}

TEST_F(MeshFormatsTest, LandXmlIsWellFormed) {
  if (!have_xmllint()) GTEST_SKIP() << "xmllint not installed (Debian: libxml2-utils)";
  Crs odd = mga56();
  odd.name = "a<b & \"c\"\nd";
  std::ofstream(path("tin.xml")) << landxml_text(awkward_mesh(), odd);
  const std::string cmd = "xmllint --noout " + path("tin.xml") + " 2>" + path("err.txt");
  EXPECT_EQ(std::system(cmd.c_str()), 0) << slurp(path("err.txt"));
  // The structure, through libxml2's XPath: one Surface of type TIN with the points and faces, in the
  // LandXML 1.2 namespace.
  const Mesh m = random_mesh(300, 5);
  std::ofstream(path("big.xml")) << landxml_text(m, mga56());
  auto xpath = [&](const std::string& expr) {
    const std::string c =
        "xmllint --xpath \"" + expr + "\" " + path("big.xml") + " >" + path("out.txt") + " 2>&1";
    EXPECT_EQ(std::system(c.c_str()), 0) << expr << ": " << slurp(path("out.txt"));
    std::string r = slurp(path("out.txt"));
    while (!r.empty() && r.back() == '\n') r.pop_back();
    return r;
  };
  const std::string ns = "[namespace-uri()='http://www.landxml.org/schema/LandXML-1.2']";
  EXPECT_EQ(xpath("count(/*[local-name()='LandXML']" + ns +
                  "/*[local-name()='Surfaces']/*[local-name()='Surface'])"),
            "1");
  EXPECT_EQ(xpath("string(//*[local-name()='Definition']/@surfType)"), "TIN");
  EXPECT_EQ(xpath("count(//*[local-name()='Pnts']/*[local-name()='P'])"), std::to_string(m.vertices.size()));
  EXPECT_EQ(xpath("count(//*[local-name()='Faces']/*[local-name()='F'])"),
            std::to_string(m.triangles.size()));
  EXPECT_EQ(xpath("string(//*[local-name()='CoordinateSystem']/@epsgCode)"), "7856");
  EXPECT_EQ(xpath("string(//*[local-name()='Metric']/@linearUnit)"), "meter");
}

// Validation against the LandXML 1.2 schema itself. The schema (LandXML-1.2.xsd, posted 2008-07-29 by
// LandXML.org) carries no license statement, so it is not kept in tests/data: give its path in
// CDTGPU_LANDXML_XSD to run this test (docs/outputs.md says where copies are).
TEST_F(MeshFormatsTest, LandXmlValidatesAgainstTheSchemaWhenGivenOne) {
  const char* xsd = std::getenv("CDTGPU_LANDXML_XSD");
  if (!xsd || !*xsd) GTEST_SKIP() << "set CDTGPU_LANDXML_XSD to a copy of LandXML-1.2.xsd (not redistributable here)";
  if (!have_xmllint()) GTEST_SKIP() << "xmllint not installed (Debian: libxml2-utils)";
  ASSERT_TRUE(std::filesystem::exists(xsd)) << xsd;
  Crs odd = mga56();
  odd.name = "a<b & \"c\"\nd";
  std::ofstream(path("odd.xml")) << landxml_text(awkward_mesh(), odd);
  std::ofstream(path("big.xml")) << landxml_text(random_mesh(300, 5), mga56(), 86400 * 365);
  std::ofstream(path("nocrs.xml")) << landxml_text(small_mesh(), Crs{});
  for (const char* f : {"odd.xml", "big.xml", "nocrs.xml"}) {
    const std::string cmd =
        "xmllint --noout --schema '" + std::string(xsd) + "' " + path(f) + " 2>" + path("err.txt");
    EXPECT_EQ(std::system(cmd.c_str()), 0) << f << ": " << slurp(path("err.txt"));
  }
}

TEST_F(MeshFormatsTest, SourceDateEpochFixesTheStamp) {
  ::setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
  EXPECT_EQ(output_timestamp(), std::time_t(1700000000));
  ::unsetenv("SOURCE_DATE_EPOCH");
  EXPECT_GT(output_timestamp(), std::time_t(1700000000));
}

TEST_F(MeshFormatsTest, TwoDmTextIsExact) {
  std::ostringstream out;
  write_2dm(small_mesh(), mga56(), out);
  EXPECT_EQ(out.str(),
            "MESH2D\nMESHNAME \"GDA2020 / MGA zone 56\"\nNUM_MATERIALS_PER_ELEM 1\n"
            "ND 1 500000 6000000 10.5\nND 2 500010 6000000 11\nND 3 500000.25 6000010 12\nND 4 500010 "
            "6000010 -0.1\n"
            "E3T 1 1 2 3 1\nE3T 2 2 4 3 1\n");
}

TEST_F(MeshFormatsTest, BothRoundTripExactlyThroughTheFilesAndWriteThePrj) {
  const Crs crs = mga56();
  for (const char* file : {"tin.xml", "tin.2dm"}) {
    for (const Mesh& m : {awkward_mesh(), random_mesh(30000, 11), Mesh{}}) {
      WriteOptions o;
      o.format = format_from_extension(file);
      write_mesh_file(m, crs, o, path(file));
      expect_identical(m, read_mesh_file(path(file)), file);
    }
    EXPECT_EQ(slurp(path("tin.prj")), crs.wkt);
  }
  EXPECT_EQ(entries(), (std::vector<std::string>{"tin.2dm", "tin.prj", "tin.xml"}));
  EXPECT_EQ(parse_format("LandXML"), MeshFormat::LandXml);
  EXPECT_EQ(parse_format("2dm"), MeshFormat::Sms2dm);
}

TEST_F(MeshFormatsTest, ABadTriangleLeavesNoFile) {
  Mesh m = small_mesh();
  m.triangles.push_back({0, 1, 7});
  for (const char* file : {"tin.xml", "tin.2dm"}) {
    WriteOptions o;
    o.format = format_from_extension(file);
    EXPECT_THROW(write_mesh_file(m, Crs{}, o, path(file)), std::runtime_error);
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(MeshFormatsTest, ReadersNameTheFileAndLine) {
  auto message = [&](const std::string& name, const std::string& text) -> std::string {
    std::ofstream(path(name)) << text;
    try {
      read_mesh_file(path(name));
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(
      message("a.2dm", "MESH2D\nND 1 0 0 0\nND 2 1 0 0\nE3T 1 1 2 3 1\n").find("a.2dm:4: E3T names node 3"),
      std::string::npos);
  EXPECT_NE(message("b.2dm", "MESH2D\nND 1 0 zero 0\n").find("b.2dm:2: ND must be followed by id x y z"),
            std::string::npos);
  EXPECT_NE(message("c.2dm", "ND 1 0 0 0\n").find("c.2dm:1: a 2DM mesh starts with MESH2D"),
            std::string::npos);
  EXPECT_NE(message("d.2dm", "MESH2D\nE4Q 1 1 2 3 4 1\n").find("d.2dm:2: element E4Q is not a triangle"),
            std::string::npos);
  EXPECT_NE(message("a.xml", "<LandXML>\n<Pnts>\n<P id=\"1\">0 0</P>\n</Pnts></LandXML>\n")
                .find("a.xml:3: <P> must hold three finite numbers"),
            std::string::npos);
  EXPECT_NE(
      message("b.xml", "<LandXML>\n<Pnts>\n<P id=\"1\">0 0 0</P>\n</Pnts>\n<Faces>\n<F>1 1 2</F>\n</Faces>\n")
          .find("b.xml:6: <F> names point id 2"),
      std::string::npos);
  EXPECT_NE(message("c.xml", "<LandXML/>\n").find("no <Pnts>"), std::string::npos);
}

TEST_F(MeshFormatsTest, TwoDmNodesMayFollowTheirElementsAndIdsNeedNotStartAtOne) {
  std::ofstream(path("x.2dm"))
      << "MESH2D\r\nE3T 5 30 10 20 1\r\nND 10 0 0 1\r\nND 20 1 0 2\r\nND 30 0 1 3\r\n";
  const Mesh m = read_mesh_file(path("x.2dm"));
  ASSERT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(m.vertices[2], (Point3{0, 1, 3}));
  EXPECT_EQ(m.triangles, (Triangles{{2, 0, 1}}));
}

}  // namespace
}  // namespace cdtgpu
