// For the GeoTIFF tests: a scratch folder, shell commands, GDAL's tools when installed, and GeoTIFFs written
// with libtiff + libgeotiff directly (so CI without gdal-bin still reads real files).
#pragma once
#include <geokeys.h>
#include <geotiffio.h>
#include <geovalues.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <xtiffio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace cdtgpu::test {

namespace fs = std::filesystem;

struct Scratch {
  fs::path dir;
  Scratch() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = fs::temp_directory_path() /
          ("cdtgpu_tiff_" + std::to_string(::getpid()) + "_" + (info ? std::string(info->name()) : "x"));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
};

inline int shell(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline bool have_tool(const std::string& name) {
  return shell("command -v " + name + " >/dev/null 2>&1") == 0;
}

inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

inline void put(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// The sample types a DEM GeoTIFF may hold.
enum class Type { u8, i8, u16, i16, u32, i32, u64, i64, f32, f64 };
inline const std::vector<Type> all_types = {Type::u8,  Type::i8,  Type::u16, Type::i16, Type::u32,
                                            Type::i32, Type::u64, Type::i64, Type::f32, Type::f64};
inline const char* type_name(Type t) {
  static const char* const n[] = {"u8", "i8", "u16", "i16", "u32", "i32", "u64", "i64", "f32", "f64"};
  return n[int(t)];
}

struct TiffOptions {
  Type type = Type::f32;
  uint32_t width = 37, height = 23;
  bool tiled = false;
  uint32_t block = 16;  // tile side, or rows per strip
  uint16_t compression = COMPRESSION_NONE;
  uint16_t predictor = 0;
  uint16_t samples = 1;
  bool point = false;                              // PixelIsPoint
  bool raster_type_key = true;                     // write GTRasterTypeGeoKey
  std::string nodata;                              // GDAL_NODATA text, none when empty
  double X = 300000, Y = 6250046, sx = 2, sy = 2;  // tiepoint (0, 0) -> (X, Y), pixel scale
  bool georef = true;
  std::vector<double> matrix;  // ModelTransformation instead of the tiepoint and scale
  int pcs = 7856;  // ProjectedCSTypeGeoKey (0: none; KvUserDefined: with `projection` and `datum`)
  int gcs = 0;     // GeographicTypeGeoKey, for a geographic raster (pcs 0)
  int projection = 0, datum = 0;
  bool bigtiff = false;
};

template <typename T>
void fill(std::vector<unsigned char>& bytes, const std::vector<double>& v) {
  bytes.resize(v.size() * sizeof(T));
  for (size_t i = 0; i < v.size(); ++i) {
    const T x = T(v[i]);
    std::memcpy(bytes.data() + i * sizeof(T), &x, sizeof x);
  }
}

// Writes `values` (row-major, height x width x samples) as a GeoTIFF with libtiff's own encoders.
inline void write_tiff(const std::string& path, const TiffOptions& o, const std::vector<double>& values) {
  static const bool once = (XTIFFInitialize(), true);
  (void)once;
  const Type t = o.type;
  const int bits = t == Type::u8 || t == Type::i8                       ? 8
                   : t == Type::u16 || t == Type::i16                   ? 16
                   : t == Type::u32 || t == Type::i32 || t == Type::f32 ? 32
                                                                        : 64;
  const uint16_t format = t == Type::f32 || t == Type::f64 ? SAMPLEFORMAT_IEEEFP
                          : t == Type::i8 || t == Type::i16 || t == Type::i32 || t == Type::i64
                              ? SAMPLEFORMAT_INT
                              : SAMPLEFORMAT_UINT;
  std::vector<unsigned char> bytes;
  switch (t) {
    case Type::u8:
      fill<uint8_t>(bytes, values);
      break;
    case Type::i8:
      fill<int8_t>(bytes, values);
      break;
    case Type::u16:
      fill<uint16_t>(bytes, values);
      break;
    case Type::i16:
      fill<int16_t>(bytes, values);
      break;
    case Type::u32:
      fill<uint32_t>(bytes, values);
      break;
    case Type::i32:
      fill<int32_t>(bytes, values);
      break;
    case Type::u64:
      fill<uint64_t>(bytes, values);
      break;
    case Type::i64:
      fill<int64_t>(bytes, values);
      break;
    case Type::f32:
      fill<float>(bytes, values);
      break;
    case Type::f64:
      fill<double>(bytes, values);
      break;
  }
  TIFF* tif = XTIFFOpen(path.c_str(), o.bigtiff ? "w8" : "w");
  ASSERT_NE(tif, nullptr);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, o.width);
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, o.height);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, o.samples);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, format);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tif, TIFFTAG_COMPRESSION, o.compression);
  if (o.predictor) TIFFSetField(tif, TIFFTAG_PREDICTOR, o.predictor);
  if (!o.nodata.empty()) {
    // Declared as GDAL does (ASCII without a count), so libtiff writes it as GDAL would.
    static const TIFFFieldInfo info[] = {
        {42113, -1, -1, TIFF_ASCII, FIELD_CUSTOM, 1, 0, const_cast<char*>("GDALNoDataValue")}};
    TIFFMergeFieldInfo(tif, info, 1);
    TIFFSetField(tif, 42113, o.nodata.c_str());
  }
  if (o.georef && o.matrix.empty()) {
    const double tie[6] = {0, 0, 0, o.X, o.Y, 0}, scale[3] = {o.sx, o.sy, 0};
    TIFFSetField(tif, TIFFTAG_GEOTIEPOINTS, 6, tie);
    TIFFSetField(tif, TIFFTAG_GEOPIXELSCALE, 3, scale);
  } else if (o.georef) {
    TIFFSetField(tif, TIFFTAG_GEOTRANSMATRIX, 16, o.matrix.data());
  }
  GTIF* gt = GTIFNew(tif);
  if (o.raster_type_key)
    GTIFKeySet(gt, GTRasterTypeGeoKey, TYPE_SHORT, 1, o.point ? RasterPixelIsPoint : RasterPixelIsArea);
  if (o.pcs) {
    GTIFKeySet(gt, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
    GTIFKeySet(gt, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, o.pcs);
    if (o.projection) GTIFKeySet(gt, ProjectionGeoKey, TYPE_SHORT, 1, o.projection);
    if (o.datum) GTIFKeySet(gt, GeogGeodeticDatumGeoKey, TYPE_SHORT, 1, o.datum);
  } else if (o.gcs) {
    GTIFKeySet(gt, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeGeographic);
    GTIFKeySet(gt, GeographicTypeGeoKey, TYPE_SHORT, 1, o.gcs);
  }
  GTIFWriteKeys(gt);
  GTIFFree(gt);
  const size_t row = size_t(o.width) * o.samples * size_t(bits / 8);
  if (o.tiled) {
    TIFFSetField(tif, TIFFTAG_TILEWIDTH, o.block);
    TIFFSetField(tif, TIFFTAG_TILELENGTH, o.block);
    const size_t px = size_t(o.samples) * size_t(bits / 8);
    std::vector<unsigned char> tile(size_t(o.block) * o.block * px);
    for (uint32_t r0 = 0; r0 < o.height; r0 += o.block)
      for (uint32_t c0 = 0; c0 < o.width; c0 += o.block) {
        std::fill(tile.begin(), tile.end(), 0);
        for (uint32_t r = r0; r < std::min(o.height, r0 + o.block); ++r)
          for (uint32_t c = c0; c < std::min(o.width, c0 + o.block); ++c)
            std::memcpy(tile.data() + (size_t(r - r0) * o.block + (c - c0)) * px,
                        bytes.data() + r * row + c * px, px);
        ASSERT_GE(TIFFWriteTile(tif, tile.data(), c0, r0, 0, 0), 0);
      }
  } else {
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, o.block);
    for (uint32_t r = 0; r < o.height; ++r)
      ASSERT_EQ(TIFFWriteScanline(tif, bytes.data() + r * row, r, 0), 1);
  }
  XTIFFClose(tif);
}

// An ESRI ASCII grid of the same cells: the corner (PixelIsArea) or centre (PixelIsPoint) of the southwest
// cell, values as the shortest text of their double.
inline std::string asc_text(const TiffOptions& o, const std::vector<double>& values,
                            const std::string& nodata) {
  std::ostringstream s;
  s.precision(17);
  const double south = o.Y - double(o.height) * o.sy;
  if (o.point)
    s << "ncols " << o.width << "\nnrows " << o.height << "\nxllcenter " << o.X << "\nyllcenter "
      << o.Y - double(o.height - 1) * o.sy;
  else
    s << "ncols " << o.width << "\nnrows " << o.height << "\nxllcorner " << o.X << "\nyllcorner " << south;
  s << "\ncellsize " << o.sx << "\n";
  if (!nodata.empty()) s << "NODATA_value " << nodata << "\n";
  for (uint32_t r = 0; r < o.height; ++r) {
    for (uint32_t c = 0; c < o.width; ++c) s << (c ? " " : "") << values[size_t(r) * o.width + c];
    s << "\n";
  }
  return s.str();
}

}  // namespace cdtgpu::test
