// A finished TIN (the mesh as written: canonical, after regions and trimming) on the device, for the passes
// that derive grids and contour lines from it. The CDT's own device buffers hold (x, y) and slots, not the
// final triangle list, so the mesh is uploaded again: 24 bytes a vertex, 12 a triangle.
//
//   gpu::DeviceTin tin = gpu::upload_tin(ctx, mesh);
//   Raster dem = rasteriser.rasterise(tin, grid_for(mesh, 1.0));   // gpu/raster.hpp
//   std::vector<Contour> lines = contourer.lines(tin, mesh, 10.0);  // gpu/contours.hpp
#pragma once
#include <cstdint>

#include "core/model.hpp"
#include "gpu/buffers.hpp"
#include "gpu/context.hpp"

namespace cdtgpu::gpu {

struct DeviceTin {
  Buffer xyz;   // double x, y, z per vertex
  Buffer tris;  // uint a, b, c per triangle, mesh order
  uint32_t num_vertices = 0;
  uint32_t num_triangles = 0;
};

// Throws DeviceError when a buffer would exceed maxStorageBufferRange (about 5.5M vertices on lavapipe).
DeviceTin upload_tin(const Context& ctx, const Mesh& mesh);

}  // namespace cdtgpu::gpu
