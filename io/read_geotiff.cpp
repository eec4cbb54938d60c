// GeoTIFF DEM reader (io/geotiff.hpp). The file is mapped once; every strip or tile is decoded into one image
// of native samples by the thread that picks it (each thread has its own libtiff handle over the same bytes),
// then rows are turned into vertices in parallel, in row-major order as the .asc reader gives them.
#include <geokeys.h>
#include <geovalues.h>
#include <spdlog/spdlog.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <xtiffio.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "core/big_array.hpp"
#include "io/geotiff.hpp"
#include "io/geotiff_lib.hpp"
#include "io/mapped_files.hpp"
#include "io/tiff_memory.hpp"

namespace cdtgpu {

namespace {

enum class Sample { u, i, f };

// Real tiles are at most a few MiB (4096 x 4096 doubles: 128 MiB); a header claiming more is damage.
constexpr uint64_t kMaxTileBytes = uint64_t(1) << 30;

struct Layout {
  uint32_t width = 0, height = 0;
  uint16_t bits = 0;
  Sample sample = Sample::u;
  bool tiled = false;
  uint32_t block_w = 0, block_h = 0;  // a tile, or a strip (the whole width, rows per strip)
  uint32_t across = 1;                // blocks per block row
  uint32_t blocks = 0;
  size_t bytes() const { return bits / 8; }
  uint64_t block_bytes() const { return uint64_t(block_w) * block_h * bytes(); }
  // Cells decoded, edge tiles' padding included.
  uint64_t padded_cells() const {
    return uint64_t(across) * block_w * ((uint64_t(height) + block_h - 1) / block_h) * block_h;
  }
  std::string block_name(uint32_t b) const {
    if (!tiled) return "strip " + std::to_string(b);
    return "tile " + std::to_string(b) + " (tile row " + std::to_string(b / across) + ", column " +
           std::to_string(b % across) + ")";
  }
  uint32_t block_of(uint64_t row, uint64_t col) const {
    return uint32_t(row / block_h) * across + (tiled ? uint32_t(col / block_w) : 0);
  }
};

struct Georef {
  double X = 0, Y = 0, I = 0, J = 0, sx = 0, ey = 0;  // ey: the y step per row (-sy)
  double half = 0.5;                                  // 0 for PixelIsPoint
  double x(uint64_t col) const { return X + (double(col) - I + half) * sx; }
  double y(uint64_t row) const { return Y + (double(row) - J + half) * ey; }
};

struct Nodata {
  bool has = false;
  double value = 0;
};

template <typename T>
T get_defaulted(TIFF* t, ttag_t tag) {
  T v{};
  TIFFGetFieldDefaulted(t, tag, &v);
  return v;
}

Layout read_layout(TIFF* t, const std::string& name) {
  Layout l;
  if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &l.width) || !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &l.height) ||
      l.width == 0 || l.height == 0)
    throw InputError(name, 0, "the TIFF has no image (width or height missing or 0)");
  const auto spp = get_defaulted<uint16_t>(t, TIFFTAG_SAMPLESPERPIXEL);
  if (spp != 1)
    throw InputError(name, 0, "has " + std::to_string(spp) + " bands (samples per pixel); a DEM has one");
  l.bits = get_defaulted<uint16_t>(t, TIFFTAG_BITSPERSAMPLE);
  const auto format = get_defaulted<uint16_t>(t, TIFFTAG_SAMPLEFORMAT);
  const bool int_bits = l.bits == 8 || l.bits == 16 || l.bits == 32 || l.bits == 64;
  if ((format == SAMPLEFORMAT_UINT || format == SAMPLEFORMAT_INT) && int_bits)
    l.sample = format == SAMPLEFORMAT_UINT ? Sample::u : Sample::i;
  else if (format == SAMPLEFORMAT_IEEEFP && (l.bits == 32 || l.bits == 64))
    l.sample = Sample::f;
  else
    throw InputError(name, 0,
                     "samples of " + std::to_string(l.bits) + " bits, sample format " +
                         std::to_string(format) +
                         ": cdtgpu reads 8, 16, 32 and 64-bit integers (formats 1 and 2) and 32 and 64-bit "
                         "floats (format 3)");
  const auto compression = get_defaulted<uint16_t>(t, TIFFTAG_COMPRESSION);
  if (!TIFFIsCODECConfigured(compression)) {
    const TIFFCodec* c = TIFFFindCODEC(compression);
    throw InputError(name, 0,
                     "compression " + std::to_string(compression) +
                         (c ? std::string(" (") + c->name + ")" : "") +
                         " is not one this build of libtiff decodes");
  }
  l.tiled = TIFFIsTiled(t);
  if (l.tiled) {
    if (!TIFFGetField(t, TIFFTAG_TILEWIDTH, &l.block_w) || !TIFFGetField(t, TIFFTAG_TILELENGTH, &l.block_h) ||
        l.block_w == 0 || l.block_h == 0)
      throw InputError(name, 0, "tiled, but without a tile width and length");
    l.across = uint32_t((uint64_t(l.width) + l.block_w - 1) / l.block_w);
  } else {
    l.block_w = l.width;
    l.block_h = std::clamp<uint32_t>(get_defaulted<uint32_t>(t, TIFFTAG_ROWSPERSTRIP), 1, l.height);
  }
  const uint64_t down = (uint64_t(l.height) + l.block_h - 1) / l.block_h;
  const uint64_t expected = down * l.across;
  const uint64_t stored = l.tiled ? TIFFNumberOfTiles(t) : TIFFNumberOfStrips(t);
  if (stored != expected)
    throw InputError(name, 0,
                     std::to_string(stored) + (l.tiled ? " tiles" : " strips") + " stored, the image needs " +
                         std::to_string(expected));
  l.blocks = uint32_t(expected);
  if (l.tiled && l.block_bytes() > kMaxTileBytes)
    throw InputError(name, 0,
                     "tiles of " + std::to_string(l.block_w) + " x " + std::to_string(l.block_h) +
                         " cells: larger than cdtgpu decodes (1 GiB a tile)");
  return l;
}

// The ModelTiepoint + ModelPixelScale pair, or a ModelTransformation without rotation.
Georef read_georef(TIFF* t, const std::string& name) {
  Georef g;
  uint16_t n_tie = 0, n_scale = 0, n_matrix = 0;
  double *tie = nullptr, *scale = nullptr, *matrix = nullptr;
  const bool has_tie = TIFFGetField(t, TIFFTAG_GEOTIEPOINTS, &n_tie, &tie) && n_tie >= 6;
  const bool has_scale = TIFFGetField(t, TIFFTAG_GEOPIXELSCALE, &n_scale, &scale) && n_scale >= 2;
  const bool has_matrix = TIFFGetField(t, TIFFTAG_GEOTRANSMATRIX, &n_matrix, &matrix) && n_matrix >= 16;
  if (has_tie && has_scale) {
    g.I = tie[0], g.J = tie[1], g.X = tie[3], g.Y = tie[4];
    g.sx = scale[0], g.ey = -scale[1];
  } else if (has_matrix) {
    if (matrix[1] != 0 || matrix[4] != 0)
      throw InputError(name, 0,
                       "its ModelTransformation rotates or shears the grid (terms " + number_text(matrix[1]) +
                           ", " + number_text(matrix[4]) + "): cdtgpu reads north-up rasters only");
    g.sx = matrix[0], g.X = matrix[3], g.ey = matrix[5], g.Y = matrix[7];
  } else if (has_tie) {
    throw InputError(name, 0,
                     std::to_string(n_tie / 6) +
                         " ground control points (ModelTiepoint) without a pixel "
                         "scale: warp it to a regular grid first (e.g. gdalwarp)");
  } else {
    throw InputError(name, 0,
                     "no georeference: neither ModelTiepoint + ModelPixelScale nor ModelTransformation tags");
  }
  for (double v : {g.X, g.Y, g.I, g.J, g.sx, g.ey})
    if (!std::isfinite(v)) throw InputError(name, 0, "its georeference holds a value that is not finite");
  if (!(g.sx > 0) || g.ey == 0)
    throw InputError(name, 0,
                     "pixel size " + number_text(g.sx) + " x " + number_text(-g.ey) +
                         ": the width must be positive and the height non-zero");
  return g;
}

Nodata read_nodata(TIFF* t, const std::string& name) {
  Nodata nd;
  const char* text = nullptr;
  if (!TIFFGetField(t, TIFFTAG_GDAL_NODATA, &text) || !text) return nd;
  std::string_view s(text);
  while (!s.empty() && (s.front() == ' ' || s.front() == '+')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.remove_suffix(1);
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), nd.value);
  if (ec != std::errc() || end != s.data() + s.size())
    throw InputError(name, 0, "its GDAL_NODATA tag '" + std::string(text) + "' is not a number");
  nd.has = true;
  return nd;
}

// The EPSG code of a user-defined UTM projection (ProjectionGeoKey 160zz north, 161zz south) on a datum
// core/projection knows, as GDAL writes when its CRS came from an ESRI .prj; 0 otherwise.
int utm_code(int projection, int datum) {
  int zone = 0;
  bool north = false;
  if (projection >= 16001 && projection <= 16060)
    zone = projection - 16000, north = true;
  else if (projection >= 16101 && projection <= 16160)
    zone = projection - 16100;
  else
    return 0;
  if (datum == 6326 || datum == 4326) return (north ? 32600 : 32700) + zone;
  if (north) return 0;
  if (datum == 6283 || datum == 4283) return 28300 + zone;
  if (datum == 1168 || datum == 7844) return 7800 + zone;
  return 0;
}

int key(GTIF* gt, geokey_t k) {
  unsigned short v = 0;
  return tiff::geotiff_lib().key_get_short(gt, k, &v, 0, 1) == 1 ? int(v) : 0;
}

// Raster type and CRS from the GeoKeys (true: PixelIsPoint). The CRS becomes source_crs_wkt when no input
// before set one. Damaged keys are an error.
bool read_geokeys(tiff::Handle& h, const std::string& name, InputSet& in) {
  uint16_t n = 0;
  uint16_t* directory = nullptr;
  // GDAL writes none for a raster without a CRS: its tiepoint is then the corner (PixelIsArea).
  if (!TIFFGetField(h.tif(), TIFFTAG_GEOKEYDIRECTORY, &n, &directory)) {
    spdlog::info("{}: no GeoKeys: cells read as PixelIsArea, no CRS", name);
    return false;
  }
  GTIF* gt = tiff::geokeys(h);
  if (!gt || !h.message().empty()) {
    if (gt) tiff::geotiff_lib().free(gt);
    throw InputError(name, 0, "its GeoKeys cannot be read: " + h.message());
  }
  const int raster = key(gt, GTRasterTypeGeoKey), model = key(gt, GTModelTypeGeoKey);
  const int pcs = key(gt, ProjectedCSTypeGeoKey), gcs = key(gt, GeographicTypeGeoKey);
  const int datum = key(gt, GeogGeodeticDatumGeoKey), projection = key(gt, ProjectionGeoKey);
  tiff::geotiff_lib().free(gt);
  std::string wkt;
  if (model == ModelTypeProjected) {
    const int code =
        pcs && pcs != KvUserDefined ? pcs : utm_code(projection, gcs && gcs != KvUserDefined ? gcs : datum);
    wkt = code == 4326 || code == 4283 || code == 7844 ? std::string() : epsg_wkt(code);
    if (wkt.empty())
      spdlog::warn(
          "{}: projected CRS {} is not one cdtgpu names (WGS 84 / UTM, GDA94 and GDA2020 / MGA): "
          "coordinates kept as read, outputs without a CRS",
          name, pcs && pcs != KvUserDefined ? "EPSG:" + std::to_string(pcs) : std::string("(user-defined)"));
  } else if (model == ModelTypeGeographic) {
    const int code = gcs && gcs != KvUserDefined ? gcs
                     : datum == 6326             ? 4326
                     : datum == 6283             ? 4283
                     : datum == 1168             ? 7844
                                                 : 0;
    wkt = code == 4326 || code == 4283 || code == 7844 ? epsg_wkt(code) : std::string();
    // Read as lon/lat on an unknown datum: --crs auto refuses it (as for such a .prj), --crs none keeps it.
    if (wkt.empty())
      wkt = "GEOGCS[\"" +
            (code ? "EPSG:" + std::to_string(code)
                  : std::string("user-defined datum " + std::to_string(datum))) +
            "\"]";
  } else if (model != 0) {
    throw InputError(name, 0,
                     "GTModelTypeGeoKey " + std::to_string(model) +
                         ": cdtgpu reads projected (1) and geographic (2) rasters");
  }
  if (in.source_crs_wkt.empty()) in.source_crs_wkt = wkt;
  return raster == RasterPixelIsPoint;
}

// The image, decoded on all cores into one buffer of native samples (row-major, width samples a row).
// Left uninitialised: every byte is decoded into (the pages first touched by the decoding threads).
BigArray<unsigned char> decode(std::string_view bytes, const std::string& name, const Layout& l,
                               const GeoTiffLimits& limits) {
  const size_t row_bytes = size_t(l.width) * l.bytes();
  BigArray<unsigned char> image(row_bytes * l.height);
  tbb::enumerable_thread_specific<std::optional<tiff::Handle>> handles;
  tbb::enumerable_thread_specific<std::vector<unsigned char>> tiles;
  std::atomic<uint32_t> first_bad{l.blocks};
  std::mutex mutex;
  std::string why;  // the message of first_bad
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, l.blocks, 1), [&](const tbb::blocked_range<uint32_t>& r) {
    std::optional<tiff::Handle>& h = handles.local();
    if (!h) h = tiff::open_read(bytes, name, limits.max_alloc);
    std::vector<unsigned char>& tile = tiles.local();
    tile.resize(l.tiled ? l.block_bytes() : 0);
    for (uint32_t b = r.begin(); b < r.end(); ++b) {
      if (b > first_bad.load()) return;
      const uint64_t row0 = uint64_t(b / l.across) * l.block_h;
      const uint32_t rows = uint32_t(std::min<uint64_t>(l.block_h, l.height - row0));
      tmsize_t got = 0, want = 0;
      int err = 0;
      const uint64_t at = TIFFGetStrileOffsetWithErr(h->tif(), b, &err);
      const uint64_t size = err ? 0 : TIFFGetStrileByteCountWithErr(h->tif(), b, &err);
      if (err || at > bytes.size() || size > bytes.size() - at) {
        std::lock_guard lock(mutex);
        if (b < first_bad) {
          first_bad = b;
          why = err ? "its offset or byte count cannot be read"
                    : "its " + std::to_string(size) + " bytes at offset " + std::to_string(at) +
                          " run past the end of the file (" + std::to_string(bytes.size()) +
                          " bytes): truncated";
        }
        continue;
      }
      if (!l.tiled) {
        want = tmsize_t(rows * row_bytes);
        got = TIFFReadEncodedStrip(h->tif(), b, image.begin() + row0 * row_bytes, want);
      } else {
        want = tmsize_t(tile.size());
        got = TIFFReadEncodedTile(h->tif(), b, tile.data(), want);
        if (got == want) {
          const uint64_t col0 = uint64_t(b % l.across) * l.block_w;
          const size_t n = size_t(std::min<uint64_t>(l.block_w, l.width - col0)) * l.bytes();
          for (uint32_t k = 0; k < rows; ++k)
            std::memcpy(image.begin() + (row0 + k) * row_bytes + col0 * l.bytes(),
                        tile.data() + size_t(k) * l.block_w * l.bytes(), n);
        }
      }
      if (got == want) continue;
      std::lock_guard lock(mutex);
      if (b < first_bad) {
        first_bad = b;
        why = got < 0 ? (h->message().empty() ? std::string("cannot be decoded") : h->message())
                      : "holds " + std::to_string(got) + " bytes of " + std::to_string(want) + " (truncated)";
      }
    }
  });
  if (first_bad < l.blocks) throw InputError(name, 0, l.block_name(first_bad) + ": " + why);
  return image;
}

template <typename T>
double load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return double(v);
}

// f(T{}) for the file's sample type.
template <typename F>
uint64_t with_sample_type(const Layout& l, F&& f) {
  switch (l.sample) {
    case Sample::u:
      return l.bits == 8    ? f(uint8_t{})
             : l.bits == 16 ? f(uint16_t{})
             : l.bits == 32 ? f(uint32_t{})
                            : f(uint64_t{});
    case Sample::i:
      return l.bits == 8    ? f(int8_t{})
             : l.bits == 16 ? f(int16_t{})
             : l.bits == 32 ? f(int32_t{})
                            : f(int64_t{});
    case Sample::f:
      break;
  }
  return l.bits == 32 ? f(float{}) : f(double{});
}

// The valid cells as vertices, appended to in.points in row-major order; returns how many. Rows in bands of
// about 64K cells: count the valid cells of each band, then write them at their offsets. T: the sample type.
template <typename T>
uint64_t cells_to_points(const unsigned char* image, const Layout& l, const Georef& g, const Nodata& nd,
                         const std::string& name, InputSet& in) {
  const size_t row_bytes = size_t(l.width) * sizeof(T);
  auto is_nodata = [&](double v) {
    return nd.has && (v == nd.value || (std::isnan(nd.value) && std::isnan(v)));
  };

  const uint64_t band_rows = std::max<uint64_t>(1, 65536 / l.width);
  const uint64_t bands = (l.height + band_rows - 1) / band_rows;
  std::vector<uint64_t> valid(bands + 1, 0);    // then its prefix sums
  std::atomic<uint64_t> first_bad{UINT64_MAX};  // the first NaN / infinite cell, row-major
  tbb::parallel_for(uint64_t(0), bands, [&](uint64_t k) {
    const unsigned char* p = image + k * band_rows * row_bytes;
    const uint64_t end = std::min<uint64_t>(l.height, (k + 1) * band_rows) * l.width;
    uint64_t n = 0;
    for (uint64_t c = k * band_rows * l.width; c < end; ++c, p += sizeof(T)) {
      const double v = load<T>(p);
      if (is_nodata(v)) continue;
      if (!std::isfinite(v)) {
        uint64_t seen = first_bad.load();
        while (c < seen && !first_bad.compare_exchange_weak(seen, c)) {
        }
        return;
      }
      ++n;
    }
    valid[k + 1] = n;
  });
  if (first_bad != UINT64_MAX) {
    const uint64_t row = first_bad / l.width, col = first_bad % l.width;
    throw InputError(name, 0,
                     l.block_name(l.block_of(row, col)) + ": the cell at row " + std::to_string(row) +
                         ", column " + std::to_string(col) + " is " +
                         number_text(load<T>(image + first_bad * sizeof(T))) +
                         (nd.has ? ", not the NODATA value " + number_text(nd.value)
                                 : ", and the file has no GDAL_NODATA tag to say it is missing"));
  }
  for (uint64_t k = 0; k < bands; ++k) valid[k + 1] += valid[k];
  const size_t first = in.points.size();
  resize_unwritten(in.points, first + valid[bands]);  // written on all cores, the earlier inputs kept
  tbb::parallel_for(uint64_t(0), bands, [&](uint64_t k) {
    Point3* out = in.points.data() + first + valid[k];
    const uint64_t row_end = std::min<uint64_t>(l.height, (k + 1) * band_rows);
    for (uint64_t row = k * band_rows; row < row_end; ++row) {
      const unsigned char* p = image + row * row_bytes;
      const double y = g.y(row);
      for (uint64_t col = 0; col < l.width; ++col, p += sizeof(T)) {
        const double v = load<T>(p);
        if (!is_nodata(v)) *out++ = Point3{g.x(col), y, v};
      }
    }
  });
  return valid[bands];
}

}  // namespace

void read_geotiff_bytes(std::string_view bytes, const std::string& name, InputSet& in,
                        const GeoTiffLimits& limits) {
  in.sources.push_back(name);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  tiff::Handle h = tiff::open_read(bytes, name, limits.max_alloc);
  const Layout l = read_layout(h.tif(), name);
  Georef g = read_georef(h.tif(), name);
  Nodata nd = read_nodata(h.tif(), name);
  if (read_geokeys(h, name, in)) g.half = 0;
  const uint64_t cells = uint64_t(l.width) * l.height;
  if (limits.max_cells && l.padded_cells() > limits.max_cells)
    throw InputError(name, 0,
                     std::to_string(l.width) + " x " + std::to_string(l.height) + " cells, more than " +
                         std::to_string(limits.max_cells) + " allowed here");
  for (uint64_t row : {uint64_t(0), uint64_t(l.height - 1)})
    for (uint64_t col : {uint64_t(0), uint64_t(l.width - 1)})
      check_finite(in, source, 0, {g.x(col), g.y(row), 0});
  // A float band's NODATA is compared as the float it stands for (GDAL writes the double of the float).
  if (nd.has && l.sample == Sample::f && l.bits == 32) nd.value = double(float(nd.value));

  const BigArray<unsigned char> image = decode(bytes, name, l, limits);
  const uint64_t valid = with_sample_type(
      l, [&](auto zero) { return cells_to_points<decltype(zero)>(image.begin(), l, g, nd, name, in); });
  in.repairs.nodata_cells += cells - valid;
  if (valid == 0) throw InputError(name, 0, "no geometry (every cell is NODATA)");
}

void read_geotiff(const std::string& path, InputSet& in) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, "is a directory, not a file");
  const files::Open f(files::open(path));
  if (!f) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  read_geotiff_bytes(f->bytes(), path, in);
}

uint64_t geotiff_cell_count(const std::string& path) {
  try {
    const files::Open f(files::open(path));
    if (!f) return 0;
    tiff::Handle h = tiff::open_read(f->bytes(), path);
    uint32_t w = 0, ht = 0;
    TIFFGetField(h.tif(), TIFFTAG_IMAGEWIDTH, &w);
    TIFFGetField(h.tif(), TIFFTAG_IMAGELENGTH, &ht);
    return uint64_t(w) * ht;
  } catch (const InputError&) {
    return 0;
  }
}

}  // namespace cdtgpu
