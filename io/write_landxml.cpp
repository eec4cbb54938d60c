// LandXML 1.2 TIN writer. The schema (www.landxml.org/schema/LandXML-1.2) wants on <LandXML> the version,
// date and time; <Units> with <Metric>; a <Surface> holds <Definition surfType="TIN"> with <Pnts> (P: id,
// "northing easting elevation") and <Faces> (F: three point ids). Civil software reads the point order
// literally, so x and y are swapped on the way out and back in.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "io/mesh_formats.hpp"
#include "io/parallel_text.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

namespace {

std::string xml_attribute(const std::string& s) {
  std::string r;
  r.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        r += "&amp;";
        break;
      case '<':
        r += "&lt;";
        break;
      case '>':
        r += "&gt;";
        break;
      case '"':
        r += "&quot;";
        break;
      case '\n':
        r += "&#10;";
        break;
      case '\r':
        r += "&#13;";
        break;
      case '\t':
        r += "&#9;";
        break;
      default:
        r += c;
    }
  }
  return r;
}

}  // namespace

std::time_t output_timestamp() {
  if (const char* s = std::getenv("SOURCE_DATE_EPOCH")) {
    char* end = nullptr;
    const long long v = std::strtoll(s, &end, 10);
    if (end != s && *end == '\0' && v >= 0) return std::time_t(v);
  }
  return std::time(nullptr);
}

void write_landxml(const Mesh& mesh, const Crs& crs, std::time_t stamp, std::ostream& out) {
  std::tm utc{};
  gmtime_r(&stamp, &utc);
  char date[16], time[16];
  std::strftime(date, sizeof date, "%Y-%m-%d", &utc);
  std::strftime(time, sizeof time, "%H:%M:%S", &utc);

  TextOut o(out);
  o.text("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
  o.text(
       "<LandXML xmlns=\"http://www.landxml.org/schema/LandXML-1.2\" "
       "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
       "xsi:schemaLocation=\"http://www.landxml.org/schema/LandXML-1.2 "
       "http://www.landxml.org/schema/LandXML-1.2/LandXML-1.2.xsd\" version=\"1.2\" date=\"")
      .text(date)
      .text("\" time=\"")
      .text(time)
      .text("\">\n");
  o.text(
      "  <Units>\n    <Metric areaUnit=\"squareMeter\" linearUnit=\"meter\" volumeUnit=\"cubicMeter\" "
      "temperatureUnit=\"celsius\" pressureUnit=\"milliBars\" angularUnit=\"decimal degrees\" "
      "directionUnit=\"decimal degrees\"/>\n  </Units>\n");
  if (crs.projected || crs.epsg || !crs.wkt.empty()) {
    o.text("  <CoordinateSystem");
    if (!crs.name.empty()) o.text(" name=\"").text(xml_attribute(crs.name)).ch('"');
    if (crs.epsg) o.text(" epsgCode=\"").number(int64_t(crs.epsg)).ch('"');
    if (!crs.wkt.empty()) o.text(" ogcWktCode=\"").text(xml_attribute(crs.wkt)).ch('"');
    o.text("/>\n");
  }
  o.text("  <Application name=\"cdtgpu\" version=\"0.1.0\"/>\n");
  o.text("  <Surfaces>\n    <Surface name=\"TIN\">\n      <Definition surfType=\"TIN\">\n        <Pnts>\n");
  o.flush();
  check_triangles(mesh);
  write_items(out, mesh.vertices.size(), 20 + 21 + 2 + 3 * (TextOut::kMaxNumberChars + 1) + 6, [&](uint64_t v, char* p) {
    const Point3& q = mesh.vertices[v];
    p = put(put_uint(put(p, "          <P id=\""), v + 1), "\">");
    p = TextOut::put_number(p, q.y);  // LandXML points are northing, easting, elevation
    p = TextOut::put_number(put(p, " "), q.x);
    p = TextOut::put_number(put(p, " "), q.z);
    return put(p, "</P>\n");
  });
  o.text("        </Pnts>\n        <Faces>\n");
  o.flush();
  write_items(out, mesh.triangles.size(), 13 + 3 * 21 + 6, [&](uint64_t t, char* p) {
    const Triangle& tri = mesh.triangles[t];
    p = put_uint(put(p, "          <F>"), uint64_t(tri[0]) + 1);
    p = put_uint(put(p, " "), uint64_t(tri[1]) + 1);
    p = put_uint(put(p, " "), uint64_t(tri[2]) + 1);
    return put(p, "</F>\n");
  });
  o.text("        </Faces>\n      </Definition>\n    </Surface>\n  </Surfaces>\n</LandXML>\n");
  o.flush();
}

}  // namespace cdtgpu
