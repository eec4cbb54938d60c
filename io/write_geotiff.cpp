// GeoTIFF grid writer (io/geotiff.hpp). libtiff compresses a tile at a time on one thread, so the tiles are
// prepared here instead, each on its own core: rounded to float, the floating-point predictor applied (TIFF
// Technical Note 3, as libtiff's fpDiff does it), DEFLATE-compressed with libdeflate; libtiff then writes
// them raw, in order, with the tags. The same raster gives the same bytes on any number of cores.
#include <geokeys.h>
#include <geovalues.h>
#include <libdeflate.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <xtiffio.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/geotiff.hpp"
#include "io/geotiff_lib.hpp"
#include "io/gis_writers.hpp"
#include "io/tiff_memory.hpp"

namespace cdtgpu {

namespace {

constexpr uint32_t kTile = 256;
constexpr int kDeflateLevel = 6;  // libdeflate's default: near its best ratio at several times zlib's speed

// One tile row of `w` floats becomes its bytes in planes, most significant byte first, each byte then the
// difference from the byte before it (predictor 3 on a little-endian host, as libtiff writes it).
void predict_row(const float* row, uint32_t w, unsigned char* out) {
  for (uint32_t i = 0; i < w; ++i) {
    uint32_t u;
    std::memcpy(&u, &row[i], 4);
    for (uint32_t p = 0; p < 4; ++p) out[p * w + i] = (unsigned char)(u >> (8 * (3 - p)));
  }
  for (uint32_t j = 4 * w - 1; j > 0; --j) out[j] = (unsigned char)(out[j] - out[j - 1]);
}

struct Compressor {
  libdeflate_compressor* c = libdeflate_alloc_compressor(kDeflateLevel);
  Compressor() {
    if (!c) throw std::bad_alloc();
  }
  Compressor(const Compressor&) = delete;
  ~Compressor() { libdeflate_free_compressor(c); }
};

// Each tile's DEFLATE stream (zlib-wrapped, as TIFF's compression 8 wants).
std::vector<std::vector<unsigned char>> compress_tiles(const Raster& r, uint32_t across, uint32_t count) {
  const GridSpec& g = r.spec;
  std::vector<std::vector<unsigned char>> tiles(count);
  tbb::enumerable_thread_specific<Compressor> compressors;
  tbb::parallel_for(uint32_t(0), count, [&](uint32_t k) {
    std::vector<float> row(kTile);
    std::vector<unsigned char> plain(size_t(kTile) * kTile * 4);
    const uint64_t row0 = uint64_t(k / across) * kTile, col0 = uint64_t(k % across) * kTile;
    for (uint32_t i = 0; i < kTile; ++i) {
      for (uint32_t j = 0; j < kTile; ++j) {
        const uint64_t rr = row0 + i, cc = col0 + j;
        row[j] = rr < g.nrows && cc < g.ncols ? float(r.at(rr, cc)) : float(Raster::nodata);
      }
      predict_row(row.data(), kTile, plain.data() + size_t(i) * kTile * 4);
    }
    libdeflate_compressor* c = compressors.local().c;
    std::vector<unsigned char>& out = tiles[k];
    out.resize(libdeflate_zlib_compress_bound(c, plain.size()));
    out.resize(libdeflate_zlib_compress(c, plain.data(), plain.size(), out.data(), out.size()));
    if (out.empty()) throw std::runtime_error("DEFLATE failed on a GeoTIFF tile");
  });
  return tiles;
}

void set_geokeys(tiff::Handle& h, const Crs& crs) {
  GTIF* gt = tiff::geokeys(h);
  const tiff::GeoTiffLib& g = tiff::geotiff_lib();
  if (!gt) throw std::runtime_error("libgeotiff: " + h.message());
  g.key_set(gt, GTRasterTypeGeoKey, TYPE_SHORT, 1, RasterPixelIsPoint);
  if (crs.epsg) {
    g.key_set(gt, GTModelTypeGeoKey, TYPE_SHORT, 1, ModelTypeProjected);
    g.key_set(gt, ProjectedCSTypeGeoKey, TYPE_SHORT, 1, crs.epsg);
    g.key_set(gt, ProjLinearUnitsGeoKey, TYPE_SHORT, 1, Linear_Meter);
  }
  if (!crs.name.empty() && crs.name != "none")
    g.key_set(gt, GTCitationGeoKey, TYPE_ASCII, 0, crs.name.c_str());
  const bool ok = g.write_keys(gt);
  g.free(gt);
  if (!ok) throw std::runtime_error("libgeotiff cannot write the GeoKeys: " + h.message());
}

}  // namespace

std::string geotiff_grid_bytes(const Raster& r, const Crs& crs) {
  const GridSpec& g = r.spec;
  if (g.ncols == 0 || g.nrows == 0 || g.ncols > UINT32_MAX || g.nrows > UINT32_MAX)
    throw std::runtime_error("a GeoTIFF grid needs 1 to 2^32-1 rows and columns");
  const uint32_t across = uint32_t((g.ncols + kTile - 1) / kTile),
                 down = uint32_t((g.nrows + kTile - 1) / kTile);
  const std::vector<std::vector<unsigned char>> tiles = compress_tiles(r, across, across * down);
  uint64_t total = 0;
  for (const auto& t : tiles) total += t.size();
  // Classic TIFF offsets are 32 bits; the tags and the tile tables need a little room beside the tiles.
  const bool bigtiff = total + 16 * uint64_t(tiles.size()) + (1 << 20) > UINT32_MAX;

  tiff::Handle h = tiff::open_write(bigtiff);
  TIFF* t = h.tif();
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, uint32_t(g.ncols));
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, uint32_t(g.nrows));
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 32);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(t, TIFFTAG_PREDICTOR, PREDICTOR_FLOATINGPOINT);
  TIFFSetField(t, TIFFTAG_TILEWIDTH, kTile);
  TIFFSetField(t, TIFFTAG_TILELENGTH, kTile);
  TIFFSetField(t, TIFFTAG_GDAL_NODATA, "-9999");
  const double scale[3] = {g.cell, g.cell, 0};
  const double tie[6] = {0, 0, 0, g.x(0), g.y(0), 0};
  TIFFSetField(t, TIFFTAG_GEOPIXELSCALE, 3, scale);
  TIFFSetField(t, TIFFTAG_GEOTIEPOINTS, 6, tie);
  set_geokeys(h, crs);
  for (uint32_t k = 0; k < tiles.size(); ++k)
    if (TIFFWriteRawTile(t, k, const_cast<unsigned char*>(tiles[k].data()), tmsize_t(tiles[k].size())) !=
        tmsize_t(tiles[k].size()))
      throw std::runtime_error("libtiff cannot write tile " + std::to_string(k) + ": " + h.message());
  return h.finish();
}

void write_geotiff_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  const std::string bytes = geotiff_grid_bytes(raster, crs);
  write_file_atomically(path,
                        [&](std::ostream& out) { out.write(bytes.data(), std::streamsize(bytes.size())); });
  write_prj_beside(path, crs);
}

}  // namespace cdtgpu
