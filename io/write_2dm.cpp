// SMS 2DM mesh writer (Aquaveo SMS; QGIS opens it as a mesh layer through MDAL): MESH2D, one ND card per
// vertex and one E3T card per triangle, 1-based ids, material 1, formatted on all cores. The CRS goes in the
// .prj beside the file.
#include <string>

#include "io/mesh_formats.hpp"
#include "io/parallel_text.hpp"
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
  o.flush();
  check_triangles(mesh);
  write_items(out, mesh.vertices.size(), 3 + 21 + 3 * (TextOut::kMaxNumberChars + 1) + 1, [&](uint64_t v, char* p) {
    const Point3& q = mesh.vertices[v];
    p = put_uint(put(p, "ND "), v + 1);
    p = TextOut::put_number(put(p, " "), q.x);
    p = TextOut::put_number(put(p, " "), q.y);
    p = TextOut::put_number(put(p, " "), q.z);
    return put(p, "\n");
  });
  write_items(out, mesh.triangles.size(), 4 + 4 * 21 + 3, [&](uint64_t t, char* p) {
    p = put_uint(put(p, "E3T "), t + 1);
    for (uint32_t v : mesh.triangles[t]) p = put_uint(put(p, " "), uint64_t(v) + 1);
    return put(p, " 1\n");
  });
}

}  // namespace cdtgpu
