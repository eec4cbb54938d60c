// The DEM grid writers: the ASCII grid formatted on all cores is byte for byte what one thread writing
// TextOut numbers in order gives (the writer before it became parallel, kept here as the reference); the
// GeoTIFF grid reads back through cdtgpu's reader and GDAL's tools as the ASCII grid's cells rounded to
// float, carries the CRS's EPSG code, and has the same bytes on every run and any number of cores; the CLI
// writes it for --grid-out x.tif.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/projection.hpp"
#include "core/raster.hpp"
#include "geotiff_helpers.hpp"
#include "io/geotiff.hpp"
#include "io/gis_writers.hpp"
#include "io/readers.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {
namespace {

using namespace test;

// Awkward doubles (thirds, tiny and huge magnitudes, negative zero) and NODATA, on an MGA-like origin.
Raster awkward_raster(uint64_t ncols, uint64_t nrows, double cell = 0.5) {
  Raster r;
  r.spec.cell = cell;
  r.spec.ix0 = 600001, r.spec.iy0 = 12500003;
  r.spec.ncols = ncols, r.spec.nrows = nrows;
  r.z.resize(ncols * nrows);
  for (uint64_t i = 0; i < r.z.size(); ++i) {
    const uint64_t k = i % 13;
    r.z[i] = k == 0   ? Raster::nodata
             : k == 1 ? 1.0 / 3 * double(i)
             : k == 2 ? -1e-7 * double(i)
             : k == 3 ? 123456.789 + double(i)
             : k == 4 ? -0.0
             : k == 5 ? 1e17 / double(i + 1)
                      : std::sin(double(i)) * 800;
  }
  return r;
}

// The ASCII writer as it was before rows were formatted in parallel.
std::string sequential_ascii(const Raster& raster) {
  std::ostringstream out;
  const GridSpec& g = raster.spec;
  TextOut o(out);
  o.text("ncols ").number(g.ncols).text("\nnrows ").number(g.nrows);
  o.text("\nxllcenter ").number(g.x(0)).text("\nyllcenter ").number(g.y(g.nrows - 1));
  o.text("\ncellsize ").number(g.cell).text("\nNODATA_value ").number(Raster::nodata).ch('\n');
  for (uint64_t row = 0; row < g.nrows; ++row) {
    for (uint64_t col = 0; col < g.ncols; ++col) {
      if (col) o.ch(' ');
      o.number(raster.at(row, col));
    }
    o.ch('\n');
  }
  o.flush();
  return out.str();
}

std::string parallel_ascii(const Raster& r) {
  std::ostringstream out;
  write_ascii_grid(r, out);
  return out.str();
}

TEST(AsciiGrid, FormattedOnAllCoresItIsTheTextOneThreadWrites) {
  // Many blocks of rows; one row longer than a block; a single cell; on one core and on all.
  for (const auto& [ncols, nrows] :
       {std::pair<uint64_t, uint64_t>{700, 300}, {70000, 3}, {1, 1}, {3, 1000}}) {
    const Raster r = awkward_raster(ncols, nrows);
    const std::string expected = sequential_ascii(r);
    EXPECT_EQ(parallel_ascii(r), expected) << ncols << " x " << nrows;
    std::string one;
    tbb::task_arena(1).execute([&] { one = parallel_ascii(r); });
    EXPECT_EQ(one, expected) << ncols << " x " << nrows;
  }
}

TEST(AsciiGrid, AFailedWriteIsReported) {
  const Raster r = awkward_raster(50, 50);
  std::ostringstream out;
  out.setstate(std::ios::badbit);
  EXPECT_THROW(write_ascii_grid(r, out), std::runtime_error);
}

Crs mga56() {
  Crs c;
  c.projected = true, c.epsg = 7856, c.zone = 56;
  c.name = "GDA2020 / MGA zone 56";
  c.wkt = epsg_wkt(7856);
  return c;
}

// The .asc's vertices with z rounded to float: what the Float32 GeoTIFF must give.
InputSet asc_vertices_as_float(const Raster& r) {
  InputSet in;
  std::istringstream s(parallel_ascii(r));
  read_ascii_grid(s, "dem.asc", in);
  for (Point3& p : in.points) p.z = double(float(p.z));
  return in;
}

TEST(GeoTiffGrid, ReadsBackAsTheAsciiGridCellForCellWithItsEpsgCode) {
  Scratch s;
  const Raster r = awkward_raster(600, 270);  // 3 x 2 tiles, the last ones padded
  write_geotiff_grid_file(r, mga56(), s.path("dem.tif"));
  EXPECT_EQ(slurp(s.path("dem.prj")), epsg_wkt(7856));
  InputSet tif;
  read_geotiff(s.path("dem.tif"), tif);
  const InputSet asc = asc_vertices_as_float(r);
  ASSERT_EQ(tif.points.size(), asc.points.size());
  for (size_t i = 0; i < asc.points.size(); ++i) ASSERT_EQ(tif.points[i], asc.points[i]) << i;
  EXPECT_EQ(tif.repairs.nodata_cells, asc.repairs.nodata_cells);
  EXPECT_EQ(tif.source_crs_wkt, epsg_wkt(7856));
}

TEST(GeoTiffGrid, TheSameBytesOnEveryRunAndAnyNumberOfCores) {
  const Raster r = awkward_raster(700, 300);
  const std::string a = geotiff_grid_bytes(r, mga56());
  EXPECT_EQ(geotiff_grid_bytes(r, mga56()), a);
  std::string one;
  tbb::task_arena(1).execute([&] { one = geotiff_grid_bytes(r, mga56()); });
  EXPECT_EQ(one, a);
  // Compressed: the awkward values leave less room, but far less than 4 bytes a cell plus tags.
  EXPECT_LT(a.size(), r.z.size() * 4);
}

TEST(GeoTiffGrid, WithoutACrsItStillReadsBack) {
  Scratch s;
  const Raster r = awkward_raster(10, 7, 2);
  Crs none;
  none.name = "none";
  write_geotiff_grid_file(r, none, s.path("dem.tif"));
  EXPECT_FALSE(fs::exists(s.path("dem.prj")));
  InputSet tif;
  read_geotiff(s.path("dem.tif"), tif);
  EXPECT_EQ(tif.source_crs_wkt, "");
  EXPECT_EQ(tif.points.size(), asc_vertices_as_float(r).points.size());
}

bool have_gdal() { return have_tool("gdalinfo") && have_tool("gdallocationinfo"); }

TEST(GeoTiffGrid, GdalReadsItsCellsNodataAndEpsgCode) {
  if (!have_gdal()) GTEST_SKIP() << "gdalinfo / gdallocationinfo not installed (Debian: gdal-bin)";
  Scratch s;
  const Raster r = awkward_raster(300, 260, 1);
  write_geotiff_grid_file(r, mga56(), s.path("dem.tif"));
  ASSERT_EQ(shell("gdalinfo -json " + s.path("dem.tif") + " > " + s.path("info.json")), 0);
  const nlohmann::json info = nlohmann::json::parse(slurp(s.path("info.json")));
  EXPECT_EQ(info["size"], nlohmann::json::array({300, 260}));
  const std::string wkt = info["coordinateSystem"]["wkt"];
  EXPECT_NE(wkt.find("ID[\"EPSG\",7856]]"), wkt.npos) << wkt;
  const auto& band = info["bands"][0];
  EXPECT_EQ(band["type"], "Float32");
  EXPECT_EQ(band["noDataValue"], -9999);
  EXPECT_EQ(band["block"], nlohmann::json::array({256, 256}));
  EXPECT_EQ(info["metadata"]["IMAGE_STRUCTURE"]["COMPRESSION"], "DEFLATE");
  EXPECT_EQ(info["metadata"]["IMAGE_STRUCTURE"]["PREDICTOR"], "3");
  // Every 7th cell, asked for by its centre's map coordinates.
  std::ostringstream where;
  where.precision(17);
  std::vector<double> expected;
  for (uint64_t i = 0; i < r.z.size(); i += 7) {
    const uint64_t row = i / r.spec.ncols, col = i % r.spec.ncols;
    where << r.spec.x(col) << " " << r.spec.y(row) << "\n";
    expected.push_back(double(float(r.z[i])));
  }
  put(s.path("where.txt"), where.str());
  ASSERT_EQ(shell("gdallocationinfo -valonly -geoloc " + s.path("dem.tif") + " < " + s.path("where.txt") +
                  " > " + s.path("values.txt")),
            0);
  std::istringstream values(slurp(s.path("values.txt")));
  for (size_t k = 0; k < expected.size(); ++k) {
    double v;
    ASSERT_TRUE(values >> v) << "value " << k;
    // gdallocationinfo prints the float with up to 17 digits: it reads back to the same float.
    ASSERT_EQ(float(v), float(expected[k])) << "cell " << k * 7;
  }
}

TEST(GeoTiffGrid, TheCliWritesTheGeoTiffForGridOutTif) {
  Scratch s;
  const std::string sample = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  const std::string cli = std::string(CDTGPU_BINARY) + " triangulate -q " + sample + "contours.shp:z=ELEV " +
                          sample + "dem.xyz -o " + s.path("tin.ply") + " --cell 10 --grid-out ";
  ASSERT_EQ(shell(cli + s.path("dem.asc")), 0);
  ASSERT_EQ(shell(cli + s.path("dem.tif")), 0);
  InputSet tif, asc;
  read_geotiff(s.path("dem.tif"), tif);
  std::istringstream a(slurp(s.path("dem.asc")));
  read_ascii_grid(a, "dem.asc", asc);
  ASSERT_EQ(tif.points.size(), asc.points.size());
  for (size_t i = 0; i < asc.points.size(); ++i) {
    ASSERT_EQ(tif.points[i].x, asc.points[i].x);
    ASSERT_EQ(tif.points[i].y, asc.points[i].y);
    ASSERT_EQ(tif.points[i].z, double(float(asc.points[i].z)));
  }
  // The run's CRS (the sample's .prj, an MGA zone) is the one the GeoTIFF's keys name.
  asc.source_crs_wkt = slurp(s.path("dem.prj"));
  const int epsg = choose_crs(asc, parse_crs("auto")).epsg;
  EXPECT_NE(epsg, 0);
  EXPECT_EQ(choose_crs(tif, parse_crs("auto")).epsg, epsg);
  const std::string first = slurp(s.path("dem.tif"));
  ASSERT_EQ(shell(cli + s.path("dem.tif")), 0);
  EXPECT_EQ(slurp(s.path("dem.tif")), first);
}

}  // namespace
}  // namespace cdtgpu
