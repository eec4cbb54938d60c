// ESRI ASCII grid writer (GDAL's AAIGrid; QGIS, ArcGIS and cdtgpu's own read_ascii_grid read it). The header
// uses xllcenter / yllcenter so the cell centres, multiples of the cell size, are written exactly. Rows are
// formatted on all cores in blocks and written in order (io/parallel_text.hpp): the text of one thread.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>

#include "io/atomic_file.hpp"
#include "io/geotiff.hpp"
#include "io/gis_writers.hpp"
#include "io/parallel_text.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

void write_ascii_grid(const Raster& raster, std::ostream& out) {
  const GridSpec& g = raster.spec;
  {
    TextOut o(out);
    o.text("ncols ").number(g.ncols).text("\nnrows ").number(g.nrows);
    o.text("\nxllcenter ").number(g.x(0)).text("\nyllcenter ").number(g.y(g.nrows - 1));
    o.text("\ncellsize ").number(g.cell).text("\nNODATA_value ").number(Raster::nodata).ch('\n');
    o.flush();
  }
  // A row a line: each value, a space or the line end after it.
  write_items(out, g.nrows, g.ncols * (TextOut::kMaxNumberChars + 1) + 1, [&](uint64_t row, char* p) {
    const double* z = raster.z.data() + row * g.ncols;
    for (uint64_t col = 0; col < g.ncols; ++col) {
      if (col) *p++ = ' ';
      p = TextOut::put_number(p, z[col]);
    }
    *p++ = '\n';
    return p;
  });
}

void write_ascii_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) { write_ascii_grid(raster, out); });
  write_prj_beside(path, crs);
}

void write_grid_file(const Raster& raster, const Crs& crs, const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".tif" || ext == ".tiff")
    write_geotiff_grid_file(raster, crs, path);
  else
    write_ascii_grid_file(raster, crs, path);
}

}  // namespace cdtgpu
