// TIN formats that GIS and engineering software open directly, beside OBJ / PLY / WKT (writers.hpp):
//   LandXML 1.2 <Surface> (12d Model, Civil 3D, Bentley OpenRoads, QGIS through plugins) and
//   SMS 2DM (QGIS mesh layers through MDAL, hydraulic models such as TUFLOW and HEC-RAS 2D).
// Usage: write_mesh / write_mesh_file dispatch here for .xml and .2dm; read_mesh_file reads both back.
//   std::ofstream f("tin.xml");
//   write_landxml(mesh, crs, std::time(nullptr), f);   // <P id="1">northing easting elevation</P>, <F>1 2
//   3</F>
#pragma once
#include <ctime>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/model.hpp"
#include "core/projection.hpp"

namespace cdtgpu {

// LandXML 1.2: one <Surface name="TIN"> with surfType="TIN", metric units, a <CoordinateSystem> with
// epsgCode (when known) and ogcWktCode (when the CRS has a WKT). Points are written "northing easting
// elevation" (y x z), as LandXML orders them; ids are 1-based in vertex order. `stamp` fills the
// required date and time attributes (UTC).
void write_landxml(const Mesh& mesh, const Crs& crs, std::time_t stamp, std::ostream& out);

// The time LandXML files are stamped with: SOURCE_DATE_EPOCH when set (reproducible output, as in
// reproducible-builds.org), else now.
std::time_t output_timestamp();

// SMS 2DM: MESH2D, "ND id x y z" per vertex, "E3T id n1 n2 n3 1" per triangle (1-based, material 1).
void write_2dm(const Mesh& mesh, const Crs& crs, std::ostream& out);

// Read back what the writers above write (and similar files): ids may be any positive integers, they are
// mapped to vertices in file order. Throw InputError naming the file and line.
Mesh read_landxml(const std::string& path, std::string_view text);
Mesh read_2dm(const std::string& path, std::string_view text);

// mesh.triangles[t], after checking its indices: a bad mesh throws part way and the atomic write leaves no
// file.
inline const Triangle& checked_triangle(const Triangle& tri, size_t t, uint64_t vertices) {
  for (uint32_t v : tri)
    if (v >= vertices)
      throw std::runtime_error("triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                               " but the mesh has " + std::to_string(vertices) + " vertices");
  return tri;
}
inline const Triangle& checked_triangle(const Mesh& mesh, size_t t) {
  return checked_triangle(mesh.triangles[t], t, mesh.vertices.size());
}

}  // namespace cdtgpu
