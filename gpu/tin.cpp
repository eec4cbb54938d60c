#include "gpu/tin.hpp"

namespace cdtgpu::gpu {

DeviceTin upload_tin(const Context& ctx, const Mesh& mesh) {
  static_assert(sizeof(Point3) == 24 && sizeof(Triangle) == 12, "Point3 is x, y, z; Triangle three uint32");
  DeviceTin tin;
  tin.num_vertices = uint32_t(mesh.vertices.size());
  tin.num_triangles = uint32_t(mesh.triangles.size());
  const uint64_t vbytes = uint64_t(tin.num_vertices) * 24, tbytes = uint64_t(tin.num_triangles) * 12;
  tin.xyz = create_buffer(ctx, vbytes, "tin vertices");
  tin.tris = create_buffer(ctx, tbytes, "tin triangles");
  if (vbytes) upload(ctx, tin.xyz, mesh.vertices.data(), vbytes);
  if (tbytes) upload(ctx, tin.tris, mesh.triangles.data(), tbytes);
  return tin;
}

}  // namespace cdtgpu::gpu
