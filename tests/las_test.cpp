// The LAS reader on files of every point format and version written by tests/las_writer.hpp (from the ASPRS
// specification): points, class / returns / withheld filters, the CRS from either VLR, damaged headers; and
// the CLI, whose mesh of a LAS file must be the mesh of the same points given as XYZ text.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/drape.hpp"
#include "core/error.hpp"
#include "core/projection.hpp"
#include "io/input_spec.hpp"
#include "io/read_las.hpp"
#include "io/readers.hpp"
#include "tests/las_writer.hpp"

using namespace cdtgpu;
using test::LasFile;
using test::LasPoint;
namespace fs = std::filesystem;

namespace {

const char* kMga56 =
    "PROJCS[\"GDA2020 / MGA zone 56\",GEOGCS[\"GDA2020\",DATUM[\"Geocentric_Datum_of_Australia_2020\","
    "SPHEROID[\"GRS 1980\",6378137,298.257222101]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]],"
    "PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\",153],"
    "PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],PARAMETER[\"false_northing\",10000000],"
    "UNIT[\"metre\",1],AUTHORITY[\"EPSG\",\"7856\"]]";

class Las : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("las_test_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }
  InputSet read(const LasFile& f, const LasFilter& filter = {}) const {
    InputSet in;
    read_las(write("t.las", test::las_bytes(f)), filter, in);
    return in;
  }
  // Expects an InputError containing `part`.
  void expect_error(const std::string& bytes, const std::string& part, const LasFilter& filter = {}) const {
    try {
      InputSet in;
      read_las(write("bad.las", bytes), filter, in);
      ADD_FAILURE() << "no InputError; expected one containing '" << part << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.las"), std::string::npos) << e.what();
    }
  }
  fs::path dir_;
};

// A varied cloud: classes 1-6 (and 40 where the format has 8-bit classes), one to three returns, every 7th point
// withheld.
std::vector<LasPoint> cloud(size_t n, bool extended_classes, uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int32_t> xy(-2'000'000, 2'000'000), z(-5000, 900'000);
  std::vector<LasPoint> pts(n);
  for (size_t i = 0; i < n; ++i) {
    LasPoint& p = pts[i];
    p.X = xy(rng);
    p.Y = xy(rng);
    p.Z = z(rng);
    p.returns = uint8_t(1 + i % 3);
    p.ret = uint8_t(1 + (i / 3) % p.returns);
    p.cls = uint8_t(extended_classes && i % 11 == 0 ? 40 : 1 + i % 6);
    p.withheld = i % 7 == 3;
    p.synthetic = i % 5 == 0;  // a flag beside the class must not change it
    p.key_point = i % 4 == 0;
    p.overlap = i % 9 == 0;
  }
  return pts;
}

Point3 expected(const LasFile& f, const LasPoint& p) {
  return {double(p.X) * f.scale[0] + f.offset[0], double(p.Y) * f.scale[1] + f.offset[1],
          double(p.Z) * f.scale[2] + f.offset[2]};
}

// The points of f the filter keeps, in file order, computed here from the rule in read_las.hpp.
Points kept(const LasFile& f, const LasFilter& filter) {
  Points out;
  for (const LasPoint& p : f.points) {
    const int cls = f.format >= 6 ? p.cls : p.cls & 31;
    if (p.withheld && !filter.keep_withheld) continue;
    if (filter.returns == LasFilter::Returns::first && p.ret > 1) continue;
    if (filter.returns == LasFilter::Returns::last && p.ret < p.returns) continue;
    if (!filter.classes.test(size_t(cls))) continue;
    out.push_back(expected(f, p));
  }
  return out;
}

TEST_F(Las, EveryPointFormatOfEveryVersionReadsItsPoints) {
  struct Case {
    int minor, format;
  };
  std::vector<Case> cases = {{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}, {2, 1}, {2, 2}, {2, 3}, {3, 4}, {3, 5}};
  for (int format = 0; format <= 10; ++format) cases.push_back({4, format});
  for (const Case& c : cases) {
    SCOPED_TRACE("LAS 1." + std::to_string(c.minor) + " format " + std::to_string(c.format));
    LasFile f;
    f.minor = c.minor;
    f.format = c.format;
    f.points = cloud(500, c.format >= 6);
    LasFilter keep_all;
    keep_all.keep_withheld = true;
    InputSet in = read(f, keep_all);
    ASSERT_EQ(in.points.size(), f.points.size());
    for (size_t i = 0; i < f.points.size(); ++i) ASSERT_EQ(in.points[i], expected(f, f.points[i])) << i;
    EXPECT_TRUE(in.lines.empty());
    // The class counts: every point kept, by its class (5 bits in formats 0-5, 8 in 6-10).
    uint64_t total = 0;
    for (const auto& [cls, n] : in.point_classes.by_class) {
      EXPECT_EQ(n.skipped, 0u);
      EXPECT_TRUE(cls <= 6 || (cls == 40 && c.format >= 6)) << cls;
      total += n.kept;
    }
    EXPECT_EQ(total, f.points.size());
  }
}

TEST_F(Las, CoordinatesAreIntegerTimesScalePlusOffset) {
  LasFile f;
  f.scale[0] = 0.01, f.scale[1] = 0.001, f.scale[2] = 0.25;
  f.offset[0] = 334000, f.offset[1] = 6250000.5, f.offset[2] = -10;
  f.points = {{.X = 12345, .Y = -2, .Z = 7}, {.X = -2147483647 - 1, .Y = 2147483647, .Z = 0}};
  InputSet in = read(f);
  ASSERT_EQ(in.points.size(), 2u);
  EXPECT_DOUBLE_EQ(in.points[0].x, 334123.45);
  EXPECT_DOUBLE_EQ(in.points[0].y, 6250000.498);
  EXPECT_EQ(in.points[0].z, -8.25);
  // In double, not float and not fused: the same bits as the expression written out.
  EXPECT_EQ(in.points[1].x, -2147483648.0 * 0.01 + 334000);
  EXPECT_EQ(in.points[1].y, 2147483647.0 * 0.001 + 6250000.5);
}

// LAS points and grid cells always come with a z (InputPart::z_complete): apply_z_rules looks for missing z
// only in the other parts, where a 2D WKT line's vertices still get 0 and are counted.
TEST_F(Las, PartsOfLasAndGridsHaveEveryZ) {
  LasFile f;
  f.points = {{.X = 1, .Y = 2, .Z = 3}, {.X = 4, .Y = 5, .Z = 6}, {.X = 7, .Y = 1, .Z = 9}};
  const std::string las = write("t.las", test::las_bytes(f));
  const std::string asc = write("g.asc", "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2\n3 4\n");
  const std::string xy = write("flat.wkt", "LINESTRING (10 10, 11 12)\n");
  InputSet in;
  const std::vector<InputPart> parts =
      read_inputs({parse_input_spec(las), parse_input_spec(asc), parse_input_spec(xy)}, ReadOptions{}, in);
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_TRUE(parts[0].z_complete);
  EXPECT_TRUE(parts[1].z_complete);
  EXPECT_FALSE(parts[2].z_complete);
  const DrapeStats stats = apply_z_rules(in, parts);
  EXPECT_EQ(stats.zero_z, (std::vector<uint64_t>{0, 0, 2}));
  for (const Point3& p : in.lines.at(parts[2].lines_begin).points) EXPECT_EQ(p.z, 0.0);
  EXPECT_EQ(in.points[0].z, 3 * f.scale[2] + f.offset[2]);
}

// A LAS file's reader gives its points' bounds (InputSet::point_extents), which choose_crs takes instead of
// reading them again; the points of other inputs are still read: lon/lat LAS points at 145-145.2 E with a text
// point at 157 E are centred on 151 E (UTM zone 56), the LAS points alone on 145.1 E (zone 55).
TEST_F(Las, ChoosingTheCrsTakesTheReadersBounds) {
  LasFile f;
  f.scale[0] = f.scale[1] = 1e-7;
  f.offset[0] = 145, f.offset[1] = -33, f.offset[2] = 0;
  f.points = {{.X = 0, .Y = 0, .Z = 1}, {.X = 2'000'000, .Y = 1'000'000, .Z = 2}, {.X = 1'000'000, .Y = -500'000, .Z = 3}};
  const std::string las = write("lonlat.las", test::las_bytes(f));
  const std::string xyz = write("far.xyz", "157 -33 5\n");
  InputSet in;
  read_inputs({parse_input_spec(las), parse_input_spec(xyz)}, ReadOptions{}, in);
  ASSERT_EQ(in.point_extents.size(), 1u);
  const InputSet::Extent& e = in.point_extents[0];
  EXPECT_EQ(e.begin, 0u);
  EXPECT_EQ(e.end, 3u);
  EXPECT_EQ(e.bounds.min_x, 145.0);
  EXPECT_EQ(e.bounds.max_x, 2'000'000 * 1e-7 + 145);
  EXPECT_EQ(e.bounds.min_y, -500'000 * 1e-7 - 33);
  EXPECT_EQ(e.bounds.max_y, 1'000'000 * 1e-7 - 33);
  const Crs both = choose_crs(in, CrsRequest{});
  EXPECT_EQ(both.zone, 56);
  InputSet scanned = in;
  scanned.point_extents.clear();
  EXPECT_EQ(choose_crs(scanned, CrsRequest{}).name, both.name);
  InputSet alone;
  read_inputs({parse_input_spec(las)}, ReadOptions{}, alone);
  EXPECT_EQ(choose_crs(alone, CrsRequest{}).zone, 55);
  project(in, both);
  EXPECT_TRUE(in.point_extents.empty()) << "projected: the bounds read are not the points' any more";
}

TEST_F(Las, ExtraBytesPerRecordAreSkipped) {
  for (int format : {1, 3, 6, 10}) {
    LasFile f;
    f.format = format;
    f.extra_bytes = 13;
    f.points = cloud(300, format >= 6);
    EXPECT_EQ(read(f).points, kept(f, {})) << format;
  }
}

TEST_F(Las, ClassReturnsAndWithheldFilters) {
  for (int format : {0, 3, 6, 8}) {
    SCOPED_TRACE(format);
    LasFile f;
    f.format = format;
    f.points = cloud(2000, format >= 6);
    LasFilter ground;
    ground.classes.reset();
    ground.classes.set(2);
    LasFilter several = ground;
    several.classes.set(5);
    several.classes.set(40);
    LasFilter last;
    last.returns = LasFilter::Returns::last;
    LasFilter first_kept;
    first_kept.returns = LasFilter::Returns::first;
    first_kept.keep_withheld = true;
    for (const LasFilter& filter : {LasFilter{}, ground, several, last, first_kept}) {
      InputSet in = read(f, filter);
      EXPECT_EQ(in.points, kept(f, filter));
      // Kept + skipped is every point; skipped by reason adds up.
      uint64_t kept_n = 0, skipped_n = 0;
      for (const auto& [cls, n] : in.point_classes.by_class) kept_n += n.kept, skipped_n += n.skipped;
      EXPECT_EQ(kept_n, in.points.size());
      EXPECT_EQ(kept_n + skipped_n, f.points.size());
      const PointClassCounts& pc = in.point_classes;
      EXPECT_EQ(pc.withheld + pc.other_returns + pc.other_classes, skipped_n);
    }
    // Class 40 exists only where classes have 8 bits.
    InputSet in = read(f, several);
    EXPECT_EQ(in.point_classes.by_class.count(40), format >= 6 ? 1u : 0u);
    EXPECT_EQ(in.point_classes.withheld, uint64_t((2000 + 3) / 7));
  }
}

TEST_F(Las, ManyPointsDecodedInRangesKeepFileOrder) {
  LasFile f;
  f.format = 7;
  f.points = cloud(300'000, true, 9);
  LasFilter filter;
  filter.classes.reset();
  filter.classes.set(2);
  filter.classes.set(3);
  filter.returns = LasFilter::Returns::last;
  EXPECT_EQ(read(f, filter).points, kept(f, filter));
}

TEST_F(Las, CrsFromTheWktVlrOrTheGeoKeys) {
  LasFile f;
  f.points = cloud(50, false);
  f.vlrs = {{"other", 7, "ignored"}, test::wkt_vlr(kMga56)};
  InputSet in = read(f);
  EXPECT_EQ(in.source_crs_wkt, kMga56);
  EXPECT_EQ(choose_crs(in, {}).epsg, 7856);

  // The same WKT as an extended VLR after the points (LAS 1.4).
  f.vlrs.clear();
  f.evlrs = {test::wkt_vlr(kMga56)};
  EXPECT_EQ(choose_crs(read(f), {}).epsg, 7856);

  // GeoKeys: ProjectedCSTypeGeoKey 28355 (GDA94 / MGA zone 55).
  f.evlrs.clear();
  f.minor = 2;
  f.vlrs = {test::geokeys_vlr(3072, 28355)};
  in = read(f);
  EXPECT_NE(in.source_crs_wkt.find("GDA_1994_MGA_Zone_55"), std::string::npos) << in.source_crs_wkt;
  EXPECT_EQ(choose_crs(in, {}).epsg, 28355);

  // GeographicTypeGeoKey 7844 (GDA2020 lon/lat): projected to the MGA zone of the data.
  f.scale[0] = f.scale[1] = 1e-7;
  f.offset[0] = 151, f.offset[1] = -33.8;
  f.vlrs = {test::geokeys_vlr(2048, 7844)};
  in = read(f);
  const Crs crs = choose_crs(in, {});
  EXPECT_TRUE(crs.from_geographic);
  EXPECT_EQ(crs.epsg, 7856);
  // Lon/lat outside its range under a geographic CRS is damage.
  f.offset[0] = 500000;
  expect_error(test::las_bytes(f), "geographic");
  // A geographic datum cdtgpu does not project is refused; an unknown projected code is kept as read.
  f.offset[0] = 151;
  f.vlrs = {test::geokeys_vlr(2048, 4269)};
  expect_error(test::las_bytes(f), "4269");
  f.offset[0] = 500000, f.offset[1] = 6000000, f.scale[0] = f.scale[1] = 0.01;
  f.vlrs = {test::geokeys_vlr(3072, 2193)};
  in = read(f);
  EXPECT_EQ(in.source_crs_wkt, "");
  EXPECT_EQ(in.points.size(), kept(f, {}).size());
}

TEST_F(Las, PointCountsLegacyAnd64Bit) {
  LasFile f;
  f.format = 1;
  f.points = cloud(100, false);
  f.count64 = 0;  // a 1.4 writer that filled only the legacy count
  EXPECT_EQ(read(f).points, kept(f, {}));
  f.count64 = -1;
  f.legacy_count = 0;  // only the 64-bit count
  EXPECT_EQ(read(f).points, kept(f, {}));
  f.legacy_count = 99;
  expect_error(test::las_bytes(f), "point counts disagree: legacy number of point records 99, number of point records 100");
}

TEST_F(Las, DamagedFilesNameTheFieldOrThePoint) {
  LasFile f;
  f.format = 3;
  f.points = cloud(100, false);
  const std::string good = test::las_bytes(f);
  expect_error("", "not a LAS file");
  expect_error("LASX" + good.substr(4), "not a LAS file");
  expect_error(good.substr(0, 200), "truncated: 200 bytes, shorter than a LAS header");
  // Ends inside the points: the header's count, the record size and what the file has room for.
  expect_error(good.substr(0, good.size() - 10),
               "truncated: the header gives 100 points of 34 bytes from byte 375, the file has " +
                   std::to_string(good.size() - 10) + " bytes (room for 99)");
  auto patched = [&](size_t at, const std::string& bytes) {
    std::string b = good;
    b.replace(at, bytes.size(), bytes);
    return b;
  };
  expect_error(patched(24, std::string("\x02\x00", 2)), "LAS version 2.0 is not supported");
  expect_error(patched(104, "\x0b"), "point data record format 11 is unknown");
  expect_error(patched(104, "\x83"), "LAZ-compressed");
  expect_error(patched(105, std::string("\x21\x00", 2)), "record length 33 is shorter than format 3's 34 bytes");
  const double zero = 0, nan = std::nan("");
  expect_error(patched(139, std::string(reinterpret_cast<const char*>(&zero), 8)), "y scale factor 0");
  expect_error(patched(171, std::string(reinterpret_cast<const char*>(&nan), 8)), "z offset nan is not a finite");
  expect_error(patched(94, std::string("\x00\x01", 2)), "header size 256 is less than LAS 1.4's 375 bytes");
  // A VLR longer than the room before the points.
  f.vlrs = {test::wkt_vlr(kMga56)};
  std::string b = test::las_bytes(f);
  b[375 + 20] = char(0xff), b[375 + 21] = char(0xff);
  expect_error(b, "VLR 1 (65535 bytes at byte 429) runs into the point data");
  // An EVLR past the end.
  f.vlrs.clear();
  f.evlrs = {test::wkt_vlr(kMga56)};
  b = test::las_bytes(f);
  expect_error(b.substr(0, b.size() - 5), "extended VLR 1 gives");
  const uint64_t inside = 400;
  b.replace(235, 8, reinterpret_cast<const char*>(&inside), 8);
  expect_error(b, "extended VLR 1 of 1 would start at byte 400, before the end of the point data (byte 3775)");
  // A scale that sends a point beyond any CRS: the point's record is named.
  f.evlrs.clear();
  f.scale[0] = 1e12;
  for (LasPoint& p : f.points) p.X = 1;
  f.points[41].X = 5000;
  f.points[41].withheld = false;
  try {
    read(f);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.record, 42u) << e.what();
    EXPECT_NE(std::string(e.what()).find("point record 42"), std::string::npos) << e.what();
  }
}

TEST_F(Las, NothingKeptSaysWhatTheFileHas) {
  LasFile f;
  f.points = cloud(60, false);
  LasFilter water;
  water.classes.reset();
  water.classes.set(9);
  expect_error(test::las_bytes(f), "no point passes the filters (60 points; by class: 1 (", water);
  f.points.clear();
  expect_error(test::las_bytes(f), "no geometry");
}

TEST(LasOptions, ClassListsReturnsAndWithheldOnTheCommandLine) {
  InputSpec s = parse_input_spec("ground.las:class=2,8,9,returns=last,withheld=keep");
  EXPECT_EQ(s.path, "ground.las");
  ASSERT_TRUE(s.las);
  EXPECT_TRUE(s.las->classes.test(2) && s.las->classes.test(8) && s.las->classes.test(9));
  EXPECT_EQ(s.las->classes.count(), 3u);
  EXPECT_EQ(s.las->returns, LasFilter::Returns::last);
  EXPECT_TRUE(s.las->keep_withheld);
  s = parse_input_spec("a.las:role=vertices,class=2");
  EXPECT_EQ(s.las->classes.count(), 1u);
  EXPECT_EQ(s.role, Role::vertices);
  EXPECT_FALSE(parse_input_spec("a.las").las);
  EXPECT_EQ(parse_input_spec("dir:2/a.las").path, "dir:2/a.las");  // not options
  EXPECT_THROW(parse_input_spec("a.las:class=256"), UsageError);
  EXPECT_THROW(parse_input_spec("a.las:returns=middle"), UsageError);
  EXPECT_THROW(parse_input_spec("a.las:withheld=maybe"), UsageError);
  EXPECT_THROW(parse_input_spec("a.las:class=2,class=3"), UsageError);
}

// The CLI: a LAS file gives the mesh of the same points given as XYZ text, byte for byte; --stats counts the
// classes; LAS options on another input and .laz are clear errors.
class LasCli : public Las {
 protected:
  struct Result {
    int code;
    std::string err;
  };
  Result run(const std::string& args) const {
    const std::string err = path("stderr.txt");
    const int status = std::system((std::string(CDTGPU_BINARY) + " " + args + " >/dev/null 2>" + err).c_str());
    std::ifstream f(err);
    std::stringstream s;
    s << f.rdbuf();
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, s.str()};
  }
  static std::string slurp(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
};

TEST_F(LasCli, MeshOfALasFileIsTheMeshOfItsPointsAsXyz) {
  LasFile f;
  f.format = 6;
  f.scale[0] = f.scale[1] = 0.01;
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int32_t> xy(0, 50'000), z(0, 30'000);
  for (int i = 0; i < 3000; ++i)
    f.points.push_back({.X = xy(rng), .Y = xy(rng), .Z = z(rng), .cls = uint8_t(i % 4 == 0 ? 2 : 5)});
  f.vlrs = {test::wkt_vlr(kMga56)};
  write("cloud.las", test::las_bytes(f));
  LasFilter ground;
  ground.classes.reset();
  ground.classes.set(2);
  std::string xyz;
  char line[128];
  for (const Point3& p : kept(f, ground)) {
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
    xyz += line;
  }
  write("ground.xyz", xyz);
  Result r = run("triangulate " + path("cloud.las") + ":class=2 -o " + path("las.ply") + " --stats " +
                 path("s.json") + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  r = run("triangulate " + path("ground.xyz") + " -o " + path("xyz.ply") + " -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string las_mesh = slurp(path("las.ply")), xyz_mesh = slurp(path("xyz.ply"));
  ASSERT_FALSE(las_mesh.empty());
  // The same triangles and coordinates; the header comment names the CRS, which only the LAS file has.
  EXPECT_EQ(las_mesh.substr(las_mesh.find("end_header")), xyz_mesh.substr(xyz_mesh.find("end_header")));
  EXPECT_NE(las_mesh.find("GDA2020 / MGA zone 56"), std::string::npos) << las_mesh.substr(0, 300);
  const nlohmann::json stats = nlohmann::json::parse(slurp(path("s.json")));
  EXPECT_EQ(stats["counts"]["las_points_by_class"]["2"]["kept"], 750);
  EXPECT_EQ(stats["counts"]["las_points_by_class"]["5"]["skipped"], 2250);
  EXPECT_EQ(stats["counts"]["las_skipped_classes"], 2250);
  EXPECT_EQ(stats["crs_epsg"], 7856);
}

TEST_F(LasCli, LazAndMisplacedOptionsAreClearErrors) {
  write("a.laz", "LASF");
  Result r = run("triangulate " + path("a.laz") + " -o " + path("a.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("laszip -i in.laz -o out.las"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pdal translate"), std::string::npos) << r.err;
  write("p.xyz", "0 0 0\n1 0 0\n0 1 0\n");
  r = run("triangulate " + path("p.xyz") + ":class=2 -o " + path("a.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("LAS inputs"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("a.ply")));
}

}  // namespace
