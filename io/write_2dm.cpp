// SMS 2DM mesh writer (Aquaveo SMS; QGIS opens it as a mesh layer through MDAL): MESH2D, one ND card per
// vertex and one E3T card per triangle, 1-based ids, material 1. The CRS goes in the .prj beside the file.
#include <string>

#include "io/mesh_formats.hpp"
#include "io/text_out.hpp"

namespace cdtgpu {

void write_2dm(const Mesh& mesh, const Crs& crs, std::ostream& out) {
  TextOut o(out);
  o.text("MESH2D\n");
  // MDAL and SMS skip unknown cards; the CRS name helps a reader who opens the file in an editor.
  if (!crs.name.empty()) {
    std::string name = crs.name;
    for (char& c : name)
      if (c == '"' || c == '\n' || c == '\r') c = ' ';
    o.text("MESHNAME \"").text(name).text("\"\n");
  }
  o.text("NUM_MATERIALS_PER_ELEM 1\n");
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Point3& p = mesh.vertices[v];
    o.text("ND ")
        .number(uint64_t(v) + 1)
        .ch(' ')
        .number(p.x)
        .ch(' ')
        .number(p.y)
        .ch(' ')
        .number(p.z)
        .ch('\n');
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = checked_triangle(mesh, t);
    o.text("E3T ").number(uint64_t(t) + 1);
    for (uint32_t v : tri) o.ch(' ').number(uint64_t(v) + 1);
    o.text(" 1\n");
  }
  o.flush();
}

}  // namespace cdtgpu
