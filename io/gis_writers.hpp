// Derived GIS outputs of a TIN: the DEM grid (core/raster.hpp) as an ESRI ASCII grid and the contour lines
// (core/contours.hpp) as WKT. Each *_file function writes whole-or-nothing (io/atomic_file.hpp) and puts the
// CRS's .prj beside the file, as write_mesh_file does.
// Usage:
//   write_ascii_grid_file(rasterise(mesh, 1.0), crs, "dem.asc");
//   write_contours_wkt_file(contour_lines(mesh, 10.0), crs, "contours.wkt");
#pragma once
#include <ostream>
#include <string>
#include <vector>

#include "core/contours.hpp"
#include "core/projection.hpp"
#include "core/raster.hpp"

namespace cdtgpu {

// ncols, nrows, xllcenter, yllcenter (the southwest cell centre), cellsize, NODATA_value -9999, then the rows
// north to south; values as the shortest text that reads back to the same double. Formatted on all cores.
void write_ascii_grid(const Raster& raster, std::ostream& out);
void write_ascii_grid_file(const Raster& raster, const Crs& crs, const std::string& path);
// By extension: .tif / .tiff a GeoTIFF (io/geotiff.hpp), anything else an ESRI ASCII grid.
void write_grid_file(const Raster& raster, const Crs& crs, const std::string& path);

// One "LINESTRING Z (x y z, ...)" line per contour, in the order given; a closed contour repeats its first
// point.
void write_contours_wkt(const std::vector<Contour>& lines, std::ostream& out);
// A GeoJSON FeatureCollection: one LineString feature per contour with properties "level" and "closed", and
// (GeoJSON 2008 style, which GDAL and QGIS honour) a "crs" member naming the EPSG code when there is one.
void write_contours_geojson(const std::vector<Contour>& lines, const Crs& crs, std::ostream& out);
// By extension: .geojson / .json GeoJSON, anything else WKT lines.
void write_contours_wkt_file(const std::vector<Contour>& lines, const Crs& crs, const std::string& path);

// The .prj beside path (path with its extension replaced), when the CRS has a WKT and path is not "-".
void write_prj_beside(const std::string& path, const Crs& crs);

}  // namespace cdtgpu
