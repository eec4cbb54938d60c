// Contour lines as WKT, one LINESTRING Z per line (QGIS opens it as a delimited-text layer with "no field
// names" and the WKT in field 1), or as GeoJSON (GDAL, QGIS and web maps open it directly, with the level as
// an attribute).
#include <cctype>
#include <filesystem>

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

void write_contours_geojson(const std::vector<Contour>& lines, const Crs& crs, std::ostream& out) {
  TextOut o(out);
  o.text("{\"type\": \"FeatureCollection\",\n");
  if (crs.epsg)
    o.text("\"crs\": {\"type\": \"name\", \"properties\": {\"name\": \"urn:ogc:def:crs:EPSG::")
        .number(int64_t(crs.epsg))
        .text("\"}},\n");
  o.text("\"features\": [");
  for (size_t k = 0; k < lines.size(); ++k) {
    const Contour& c = lines[k];
    o.text(k ? ",\n" : "\n").text("{\"type\": \"Feature\", \"properties\": {\"level\": ").number(c.level);
    o.text(", \"closed\": ").text(c.closed ? "true" : "false");
    o.text("}, \"geometry\": {\"type\": \"LineString\", \"coordinates\": [");
    for (size_t i = 0; i < c.points.size(); ++i) {
      const Point3& p = c.points[i];
      o.text(i ? ", [" : "[").number(p.x).text(", ").number(p.y).text(", ").number(p.z).ch(']');
    }
    o.text("]}}");
  }
  o.text("\n]}\n");
  o.flush();
}

void write_contours_wkt_file(const std::vector<Contour>& lines, const Crs& crs, const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  const bool geojson = ext == ".geojson" || ext == ".json";
  write_file_atomically(path, [&](std::ostream& out) {
    if (geojson)
      write_contours_geojson(lines, crs, out);
    else
      write_contours_wkt(lines, out);
  });
  write_prj_beside(path, crs);
}

}  // namespace cdtgpu
