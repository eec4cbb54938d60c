// Contour lines as WKT, one LINESTRING Z per line (QGIS opens it as a delimited-text layer with "no field names"
// and the WKT in field 1).
#include "io/atomic_file.hpp"
#include "io/gis_writers.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

void write_contours_wkt(const std::vector<Contour>& lines, std::ostream& out) {
  TextOut o(out);
  for (const Contour& c : lines) {
    o.text("LINESTRING Z (");
    for (size_t i = 0; i < c.points.size(); ++i) {
      const Point3& p = c.points[i];
      if (i) o.text(", ");
      o.number(p.x).ch(' ').number(p.y).ch(' ').number(p.z);
    }
    o.text(")\n");
  }
  o.flush();
}

void write_contours_wkt_file(const std::vector<Contour>& lines, const Crs& crs, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) { write_contours_wkt(lines, out); });
  write_prj_beside(path, crs);
}

}  // namespace cdtgpu
