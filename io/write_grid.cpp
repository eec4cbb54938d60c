// ESRI ASCII grid writer (GDAL's AAIGrid; QGIS, ArcGIS and cdtgpu's own read_ascii_grid read it). The header
// uses xllcenter / yllcenter so the cell centres, multiples of the cell size, are written exactly.
#include <filesystem>

#include "io/atomic_file.hpp"
#include "io/gis_writers.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

void write_ascii_grid(const Raster& raster, std::ostream& out) {
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
}

void write_ascii_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) { write_ascii_grid(raster, out); });
  write_prj_beside(path, crs);
}

void write_prj_beside(const std::string& path, const Crs& crs) {
  if (path == "-" || crs.wkt.empty()) return;
  const std::string prj = std::filesystem::path(path).replace_extension(".prj").string();
  write_file_atomically(prj, [&](std::ostream& out) { out << crs.wkt; });
}

}  // namespace cdtgpu
