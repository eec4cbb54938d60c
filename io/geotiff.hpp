// GeoTIFF DEMs in and DEM grids out, through libtiff and libgeotiff (no GDAL).
//
//   read_geotiff("dem.tif", in);                      // one vertex per valid cell, as an .asc gives
//   write_geotiff_grid_file(raster, crs, "dem.tif");  // Float32, tiled, DEFLATE + predictor 3, GeoKeys
//
// Reading: one band of 8-64-bit signed or unsigned integers or 32/64-bit floats, in strips or tiles, any
// compression libtiff decodes; GDAL_NODATA cells are skipped (counted as repairs.nodata_cells). The cell
// centre of row r (0 = the first stored), column c is, with the first tiepoint (I, J) -> (X, Y), the pixel
// scale (sx, sy) and h = 1/2 for PixelIsArea (the default), 0 for PixelIsPoint:
//   x = X + (c - I + h) * sx,   y = Y - (r - J + h) * sy     (double, in that order)
// which is the .asc reader's xll + (c + 1/2) * dx for the same grid. A ModelTransformation without rotation
// gives the same; with rotation, ground control points alone, no georeference, NaN or infinite values that
// are not NODATA, several bands, other sample types, codecs libtiff lacks and damaged strips or tiles are
// InputErrors naming the file (and the strip or tile). The CRS comes from the GeoKeys: a projected code (or a
// user-defined UTM projection on the WGS 84 / GDA94 / GDA2020 datum, as GDAL writes from an ESRI .prj) that
// core/projection knows becomes InputSet::source_crs_wkt as a .prj would; geographic WGS 84 / GDA94 / GDA2020
// rasters are lon/lat input. Strips and tiles are decoded on all cores, each thread with its own handle.
#pragma once
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>

#include "core/model.hpp"
#include "core/projection.hpp"
#include "core/raster.hpp"

namespace cdtgpu {

struct GeoTiffLimits {
  uint64_t max_cells = 0;  // refuse larger rasters (0: any); the fuzz target keeps its memory small with it
  uint64_t max_alloc = 0;  // libtiff's largest single allocation (0: libtiff's default)
};

void read_geotiff(const std::string& path, InputSet& in);
// The same on a whole file in memory (`name` for messages).
void read_geotiff_bytes(std::string_view bytes, const std::string& name, InputSet& in,
                        const GeoTiffLimits& limits = {});
// width x height from the header, 0 when the file is not a TIFF (an estimate for the GPU's start).
uint64_t geotiff_cell_count(const std::string& path);

// The grid as a GeoTIFF: Float32 (each double rounded to the nearest float), 256 x 256 tiles (the edge
// tiles padded with NODATA), DEFLATE with the floating-point predictor, each tile compressed on its own core
// and written in order (the same bytes on every run), PixelIsPoint with the tiepoint on the northwest cell
// centre (so centres are exact, as the .asc's xllcenter), GDAL_NODATA -9999, and GeoKeys: the EPSG code and
// name of the CRS when it has a code, else its name alone. BigTIFF when the tiles pass 4 GiB.
std::string geotiff_grid_bytes(const Raster& raster, const Crs& crs);
void write_geotiff_grid_file(const Raster& raster, const Crs& crs, const std::string& path);

}  // namespace cdtgpu
