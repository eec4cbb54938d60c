// The GeoTIFF DEM reader (io/geotiff.hpp): every sample type, strips and tiles, compressed or not,
// PixelIsArea and PixelIsPoint give the vertices the .asc reader gives for the same grid; the CRS comes from
// the GeoKeys; bad files are InputErrors naming the strip or tile. Files come from libtiff directly (always)
// and from GDAL's gdal_translate (when gdal-bin is installed), and the CLI gives the same mesh bytes for a
// .tif as for its .asc.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "geotiff_helpers.hpp"
#include "io/geotiff.hpp"
#include "io/readers.hpp"

namespace cdtgpu {
namespace {

using namespace test;

constexpr double kNodata = 99;

// Cells that fit every type, some of them NODATA; floats with a fraction a float holds exactly where the type
// is f32 (1/3 rounded to float), so the .asc text of the double is the same value.
std::vector<double> cells(const TiffOptions& o) {
  std::vector<double> v(size_t(o.width) * o.height);
  for (uint32_t r = 0; r < o.height; ++r)
    for (uint32_t c = 0; c < o.width; ++c) {
      double z = (r * 7 + c * 3) % 99;
      if (o.type == Type::i8 || o.type == Type::i16 || o.type == Type::i32 || o.type == Type::i64) z -= 50;
      if (o.type == Type::f32) z = double(float((z - 50) / 4 + 1.0 / 3));
      if (o.type == Type::f64) z = (z - 50) / 4 + 1.0 / 3;
      if ((r * 3 + c) % 11 == 0) z = kNodata;
      v[size_t(r) * o.width + c] = z;
    }
  return v;
}

InputSet read_tif(const std::string& path) {
  InputSet in;
  read_geotiff(path, in);
  return in;
}

InputSet read_asc(const std::string& text) {
  InputSet in;
  std::istringstream s(text);
  read_ascii_grid(s, "grid.asc", in);
  return in;
}

void expect_same_points(const InputSet& a, const InputSet& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    ASSERT_EQ(a.points[i], b.points[i]) << "vertex " << i;
  }
  EXPECT_EQ(a.repairs.nodata_cells, b.repairs.nodata_cells);
}

TEST(GeoTiffRead, EverySampleTypeInStripsAndTilesGivesTheAscVertices) {
  Scratch s;
  for (Type t : all_types)
    for (bool tiled : {false, true})
      for (bool point : {false, true}) {
        TiffOptions o;
        o.type = t, o.tiled = tiled, o.point = point, o.nodata = "99";
        o.block = tiled ? 16 : 5;
        SCOPED_TRACE(std::string(type_name(t)) + (tiled ? " tiled" : " stripped") +
                     (point ? " point" : " area"));
        const std::vector<double> v = cells(o);
        const std::string path = s.path("dem.tif");
        write_tiff(path, o, v);
        const InputSet tif = read_tif(path);
        const InputSet asc = read_asc(asc_text(o, v, "99"));
        expect_same_points(tif, asc);
        EXPECT_GT(tif.repairs.nodata_cells, 0u);
      }
}

TEST(GeoTiffRead, CompressedFilesDecodeTheSame) {
  Scratch s;
  struct Case {
    uint16_t compression, predictor;
    Type type;
  };
  for (const Case c : {Case{COMPRESSION_ADOBE_DEFLATE, 3, Type::f32},
                       Case{COMPRESSION_ADOBE_DEFLATE, 2, Type::i16}, Case{COMPRESSION_LZW, 2, Type::u16},
                       Case{COMPRESSION_LZW, 3, Type::f64}, Case{COMPRESSION_PACKBITS, 0, Type::u8}})
    for (bool tiled : {false, true}) {
      TiffOptions o;
      o.type = c.type, o.tiled = tiled, o.compression = c.compression, o.predictor = c.predictor,
      o.nodata = "99";
      o.width = 300, o.height = 170, o.block = tiled ? 64 : 7;  // many strips and tiles, edge tiles partial
      SCOPED_TRACE("compression " + std::to_string(c.compression) + " predictor " +
                   std::to_string(c.predictor) + (tiled ? " tiled" : " stripped"));
      const std::vector<double> v = cells(o);
      write_tiff(s.path("dem.tif"), o, v);
      expect_same_points(read_tif(s.path("dem.tif")), read_asc(asc_text(o, v, "99")));
    }
}

TEST(GeoTiffRead, BigTiffReadsAsClassicTiff) {
  Scratch s;
  TiffOptions o;
  o.type = Type::f64, o.tiled = true, o.compression = COMPRESSION_ADOBE_DEFLATE, o.nodata = "99";
  const std::vector<double> v = cells(o);
  write_tiff(s.path("classic.tif"), o, v);
  o.bigtiff = true;
  write_tiff(s.path("big.tif"), o, v);
  ASSERT_EQ(slurp(s.path("big.tif"))[2], 43);  // BigTIFF's version number
  expect_same_points(read_tif(s.path("big.tif")), read_tif(s.path("classic.tif")));
}

TEST(GeoTiffRead, OneThreadAndAllThreadsReadTheSame) {
  Scratch s;
  TiffOptions o;
  o.width = 1000, o.height = 400, o.tiled = true, o.block = 32, o.compression = COMPRESSION_ADOBE_DEFLATE;
  o.nodata = "99";
  write_tiff(s.path("dem.tif"), o, cells(o));
  InputSet one;
  tbb::task_arena(1).execute([&] { one = read_tif(s.path("dem.tif")); });
  expect_same_points(one, read_tif(s.path("dem.tif")));
}

TEST(GeoTiffRead, WithoutNodataEveryCellIsAVertexAndARasterTypeDefaultsToArea) {
  Scratch s;
  TiffOptions o;
  o.type = Type::i16, o.raster_type_key = false;
  const std::vector<double> v = cells(o);
  write_tiff(s.path("dem.tif"), o, v);
  const InputSet in = read_tif(s.path("dem.tif"));
  EXPECT_EQ(in.points.size(), v.size());
  EXPECT_EQ(in.repairs.nodata_cells, 0u);
  expect_same_points(in, read_asc(asc_text(o, v, "")));
}

TEST(GeoTiffRead, AModelTransformationWithoutRotationPlacesCellsAsTheTiepointDoes) {
  Scratch s;
  TiffOptions o;
  const std::vector<double> v = cells(o);
  write_tiff(s.path("tie.tif"), o, v);
  o.matrix = {o.sx, 0, 0, o.X, 0, -o.sy, 0, o.Y, 0, 0, 0, 0, 0, 0, 0, 1};
  write_tiff(s.path("matrix.tif"), o, v);
  expect_same_points(read_tif(s.path("matrix.tif")), read_tif(s.path("tie.tif")));
}

TEST(GeoTiffRead, TheCrsComesFromTheGeoKeys) {
  Scratch s;
  auto crs_of = [&](TiffOptions o) {
    write_tiff(s.path("crs.tif"), o, cells(o));
    return read_tif(s.path("crs.tif")).source_crs_wkt;
  };
  TiffOptions o;
  o.pcs = 28355;
  EXPECT_EQ(crs_of(o), epsg_wkt(28355));
  o.pcs = 32756;
  EXPECT_EQ(crs_of(o), epsg_wkt(32756));
  // What GDAL writes from an ESRI .prj it cannot name: a user-defined CRS, UTM zone 56 south, GDA2020 datum.
  o.pcs = KvUserDefined, o.projection = 16156, o.datum = 1168;
  EXPECT_EQ(crs_of(o), epsg_wkt(7856));
  o.projection = 16155, o.datum = 6283;
  EXPECT_EQ(crs_of(o), epsg_wkt(28355));
  // A projection cdtgpu does not name (Australian Albers): coordinates kept, no CRS recorded.
  o.pcs = 3577, o.projection = 0, o.datum = 0;
  EXPECT_EQ(crs_of(o), "");
  // Geographic rasters are lon/lat input on their datum.
  o.pcs = 0, o.gcs = 7844, o.X = 150, o.Y = -33, o.sx = o.sy = 0.001;
  EXPECT_EQ(crs_of(o), epsg_wkt(7844));
  EXPECT_NE(epsg_wkt(7844).find("GDA2020"), std::string::npos);
}

TEST(GeoTiffRead, ALonLatRasterIsProjectedLikeLonLatInput) {
  Scratch s;
  TiffOptions o;
  o.pcs = 0, o.gcs = 4283, o.X = 150.25, o.Y = -33.5, o.sx = o.sy = 1.0 / 1024;
  write_tiff(s.path("ll.tif"), o, cells(o));
  const InputSet in = read_tif(s.path("ll.tif"));
  const Crs crs = choose_crs(in, parse_crs("auto"));
  EXPECT_EQ(crs.epsg, 28356);  // GDA94 lon/lat at 150.25 E goes to MGA zone 56
}

std::string error_of(const std::string& path) {
  try {
    read_tif(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(GeoTiffRead, BadFilesAreInputErrorsNamingWhatIsWrong) {
  Scratch s;
  const std::string p = s.path("bad.tif");
  auto write = [&](TiffOptions o) {
    std::vector<double> v(size_t(o.width) * o.height * o.samples, 1.0);
    write_tiff(p, o, v);
  };
  TiffOptions o;
  o.georef = false;
  write(o);
  EXPECT_NE(error_of(p).find("no georeference"), std::string::npos) << error_of(p);
  o = {};
  o.matrix = {2, 0.5, 0, 300000, 0.5, -2, 0, 6250000, 0, 0, 0, 0, 0, 0, 0, 1};
  write(o);
  EXPECT_NE(error_of(p).find("rotates"), std::string::npos) << error_of(p);
  o = {};
  o.samples = 3;
  write(o);
  EXPECT_NE(error_of(p).find("3 bands"), std::string::npos) << error_of(p);
  o = {};
  o.sy = 0;
  write(o);
  EXPECT_NE(error_of(p).find("pixel size"), std::string::npos) << error_of(p);
  put(p, "II*\0 this is not a tiff");
  EXPECT_NE(error_of(p).find("not a TIFF"), std::string::npos) << error_of(p);
  EXPECT_NE(error_of(s.path("missing.tif")).find("no such file"), std::string::npos);
}

TEST(GeoTiffRead, NanOrInfinityThatIsNotNodataNamesItsTileAndCell) {
  Scratch s;
  TiffOptions o;
  o.type = Type::f32, o.tiled = true, o.block = 16;
  std::vector<double> v = cells(o);
  v[size_t(20) * o.width + 33] = NAN;  // tile row 1, tile column 2: tile 5
  write_tiff(s.path("nan.tif"), o, v);
  const std::string e = error_of(s.path("nan.tif"));
  EXPECT_NE(e.find("tile 5"), std::string::npos) << e;
  EXPECT_NE(e.find("row 20, column 33"), std::string::npos) << e;
  EXPECT_NE(e.find("no GDAL_NODATA"), std::string::npos) << e;
  // With NODATA "nan", NaN cells are NODATA; an infinity still is not.
  o.nodata = "nan";
  write_tiff(s.path("nan.tif"), o, v);
  const InputSet in = read_tif(s.path("nan.tif"));
  EXPECT_EQ(in.repairs.nodata_cells, 1u);
  v[size_t(3) * o.width + 4] = INFINITY;
  o.tiled = false, o.block = 2;
  write_tiff(s.path("inf.tif"), o, v);
  EXPECT_NE(error_of(s.path("inf.tif")).find("strip 1: the cell at row 3, column 4 is inf"),
            std::string::npos)
      << error_of(s.path("inf.tif"));
}

// Little-endian classic TIFF: the IFD's entry for `tag`, to damage a file on purpose.
size_t entry_of(const std::string& b, uint16_t tag) {
  uint32_t ifd;
  std::memcpy(&ifd, b.data() + 4, 4);
  uint16_t n;
  std::memcpy(&n, b.data() + ifd, 2);
  for (uint16_t k = 0; k < n; ++k) {
    uint16_t t;
    std::memcpy(&t, b.data() + ifd + 2 + 12 * k, 2);
    if (t == tag) return ifd + 2 + 12 * k;
  }
  return 0;
}

TEST(GeoTiffRead, DamagedStripsAndUnknownCompressionsNameTheStrip) {
  Scratch s;
  TiffOptions o;
  o.type = Type::f32, o.block = 4, o.compression = COMPRESSION_ADOBE_DEFLATE;
  write_tiff(s.path("ok.tif"), o, cells(o));
  std::string b = slurp(s.path("ok.tif"));
  ASSERT_EQ(b.substr(0, 4), std::string("II*\0", 4));
  // Strip 2's offset pointed past the end of the file: truncated.
  {
    std::string d = b;
    const size_t e = entry_of(d, TIFFTAG_STRIPOFFSETS);
    ASSERT_NE(e, 0u);
    uint32_t table;
    std::memcpy(&table, d.data() + e + 8, 4);
    const uint32_t past = uint32_t(d.size() + 1000);
    std::memcpy(d.data() + table + 4 * 2, &past, 4);
    put(s.path("cut.tif"), d);
    const std::string err = error_of(s.path("cut.tif"));
    EXPECT_NE(err.find("strip 2"), std::string::npos) << err;
  }
  // Strip 3's DEFLATE stream damaged.
  {
    std::string d = b;
    const size_t e = entry_of(d, TIFFTAG_STRIPOFFSETS);
    uint32_t table, at;
    std::memcpy(&table, d.data() + e + 8, 4);
    std::memcpy(&at, d.data() + table + 4 * 3, 4);
    for (int k = 0; k < 8; ++k) d[at + k] = char(0xff);
    put(s.path("bad.tif"), d);
    const std::string err = error_of(s.path("bad.tif"));
    EXPECT_NE(err.find("strip 3"), std::string::npos) << err;
  }
  // A compression code no libtiff knows.
  {
    std::string d = b;
    const size_t e = entry_of(d, TIFFTAG_COMPRESSION);
    const uint16_t code = 60000;
    std::memcpy(d.data() + e + 8, &code, 2);
    put(s.path("codec.tif"), d);
    const std::string err = error_of(s.path("codec.tif"));
    EXPECT_NE(err.find("compression 60000"), std::string::npos) << err;
  }
  // 16-bit floats and 12-bit integers are not DEM sample types cdtgpu reads.
  {
    std::string d = b;
    const size_t e = entry_of(d, TIFFTAG_BITSPERSAMPLE);
    const uint16_t bits = 12;
    std::memcpy(d.data() + e + 8, &bits, 2);
    put(s.path("bits.tif"), d);
    const std::string err = error_of(s.path("bits.tif"));
    EXPECT_NE(err.find("12 bits"), std::string::npos) << err;
  }
}

// ---- GeoTIFFs written by GDAL (gdal_translate from the .asc) ----

// Two written once by gdal_translate 3.6 and kept in tests/data (so CI without gdal-bin reads GDAL's files):
// grid_corner.asc as Int16 strips with -a_srs EPSG:7856; grid_center.asc (dx 1, dy 2) as Float32 16x16
// tiles, DEFLATE + predictor 3, AREA_OR_POINT=Point.
TEST(GeoTiffRead, CheckedInGdalFilesGiveTheirAscVertices) {
  const std::string dir = std::string(CDTGPU_SOURCE_DIR) + "/tests/data/readers/";
  for (const auto& [base, tif_name] :
       {std::pair<std::string, std::string>{"grid_corner", "grid_corner_int16.tif"},
        {"grid_center", "grid_center_float32.tif"}}) {
    SCOPED_TRACE(base);
    const std::string tif = dir + tif_name;
    InputSet asc;
    std::istringstream text(slurp(dir + base + ".asc"));
    read_ascii_grid(text, base, asc);
    expect_same_points(read_tif(tif), asc);
  }
  EXPECT_EQ(read_tif(dir + "grid_corner_int16.tif").source_crs_wkt, epsg_wkt(7856));
}

bool have_gdal() { return have_tool("gdal_translate"); }
#define SKIP_WITHOUT_GDAL() \
  if (!have_gdal())         \
  GTEST_SKIP() << "gdal_translate not installed (Debian: gdal-bin): GDAL-written GeoTIFFs not tried"

TEST(GeoTiffRead, GdalTranslateOutputsGiveTheAscVertices) {
  SKIP_WITHOUT_GDAL();
  Scratch s;
  struct Case {
    Type type;
    const char* ot;
    const char* options;
    bool point;
  };
  const Case cases[] = {
      {Type::i16, "Int16", "-co TILED=NO", false},
      {Type::i16, "Int16", "-co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 -co COMPRESS=DEFLATE", true},
      {Type::u8, "Byte", "-co TILED=NO -co COMPRESS=LZW -co PREDICTOR=2", false},
      {Type::i32, "Int32", "-co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 -co COMPRESS=PACKBITS", false},
      {Type::f32, "Float32", "-co TILED=NO -co BLOCKYSIZE=3 -co COMPRESS=DEFLATE -co PREDICTOR=3", true},
      {Type::f32, "Float32", "-co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 -co COMPRESS=LZW", false},
      {Type::f64, "Float64",
       "-co TILED=YES -co BLOCKXSIZE=32 -co BLOCKYSIZE=32 -co COMPRESS=DEFLATE "
       "-co PREDICTOR=3",
       true},
  };
  for (const Case& c : cases) {
    TiffOptions o;
    o.type = c.type, o.point = c.point;
    SCOPED_TRACE(std::string(c.ot) + " " + c.options + (c.point ? " point" : " area"));
    const std::vector<double> v = cells(o);
    const std::string asc = asc_text(o, v, "99");
    put(s.path("dem.asc"), asc);
    // GDAL reads an .asc with decimals as Float32 unless told otherwise.
    const std::string cmd =
        std::string("gdal_translate -q --config AAIGRID_DATATYPE Float64 -of GTiff -ot ") + c.ot + " " +
        c.options + (c.point ? " -mo AREA_OR_POINT=Point" : "") + " " + s.path("dem.asc") + " " +
        s.path("dem.tif");
    ASSERT_EQ(shell(cmd), 0) << cmd;
    expect_same_points(read_tif(s.path("dem.tif")), read_asc(asc));
  }
}

TEST(GeoTiffRead, GdalsCrsFromAnEsriPrjOrAnEpsgCodeIsRecognised) {
  SKIP_WITHOUT_GDAL();
  Scratch s;
  TiffOptions o;
  put(s.path("dem.asc"), asc_text(o, cells(o), "99"));
  put(s.path("dem.prj"), epsg_wkt(7856));
  ASSERT_EQ(shell("gdal_translate -q " + s.path("dem.asc") + " " + s.path("prj.tif")), 0);
  EXPECT_EQ(read_tif(s.path("prj.tif")).source_crs_wkt, epsg_wkt(7856));
  ASSERT_EQ(shell("gdal_translate -q -a_srs EPSG:28355 " + s.path("dem.asc") + " " + s.path("epsg.tif")), 0);
  EXPECT_EQ(read_tif(s.path("epsg.tif")).source_crs_wkt, epsg_wkt(28355));
}

TEST(GeoTiffRead, ATruncatedGdalFileNamesTheTileItStopsIn) {
  SKIP_WITHOUT_GDAL();
  Scratch s;
  TiffOptions o;
  o.width = 200, o.height = 100;
  put(s.path("dem.asc"), asc_text(o, cells(o), "99"));
  ASSERT_EQ(shell("gdal_translate -q -ot Float32 -co TILED=YES -co BLOCKXSIZE=64 -co BLOCKYSIZE=64 " +
                  s.path("dem.asc") + " " + s.path("dem.tif")),
            0);
  const std::string b = slurp(s.path("dem.tif"));
  put(s.path("cut.tif"), b.substr(0, b.size() - 20000));  // GDAL puts the directory first, tiles after
  const std::string err = error_of(s.path("cut.tif"));
  EXPECT_NE(err.find("cut.tif: tile "), std::string::npos) << err;
}

TEST(GeoTiffRead, TheCliWritesTheSameMeshForTheTifAsForTheAsc) {
  SKIP_WITHOUT_GDAL();
  Scratch s;
  TiffOptions o;
  o.type = Type::f32;
  put(s.path("dem.asc"), asc_text(o, cells(o), "99"));
  ASSERT_EQ(
      shell("gdal_translate -q -co TILED=YES -co BLOCKXSIZE=16 -co BLOCKYSIZE=16 -co COMPRESS=DEFLATE " +
            s.path("dem.asc") + " " + s.path("dem.tif")),
      0);
  const std::string cli = std::string(CDTGPU_BINARY) + " triangulate -q --crs none ";
  ASSERT_EQ(shell(cli + s.path("dem.asc") + " -o " + s.path("asc.ply") + " --stats " + s.path("asc.json")),
            0);
  ASSERT_EQ(shell(cli + s.path("dem.tif") + " -o " + s.path("tif.ply") + " --stats " + s.path("tif.json")),
            0);
  EXPECT_EQ(slurp(s.path("asc.ply")), slurp(s.path("tif.ply")));
  EXPECT_NE(slurp(s.path("tif.json")).find("\"nodata_cells\""), std::string::npos);
  // A bad file: exit code 2, the file named.
  put(s.path("bad.tif"), slurp(s.path("dem.tif")).substr(0, 300));
  EXPECT_EQ(shell(cli + s.path("bad.tif") + " -o " + s.path("bad.ply") + " 2>" + s.path("err.txt")), 2);
  EXPECT_NE(slurp(s.path("err.txt")).find("bad.tif"), std::string::npos);
  EXPECT_FALSE(fs::exists(s.path("bad.ply")));
}

}  // namespace
}  // namespace cdtgpu
