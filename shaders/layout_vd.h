// Push constants of the Voronoi first stage (gpu/voronoi_start.cpp, shaders/vd_*.comp), shared by C++ and GLSL.
// The method is in docs/gpu-delaunay.md, "The Voronoi first stage".
#ifndef CDTGPU_SHADERS_LAYOUT_VD_H
#define CDTGPU_SHADERS_LAYOUT_VD_H
#include "layout.h"

#ifdef __cplusplus
namespace cdtgpu::gpu::layout {
#endif

#define VD_WG 256
// vd_flood's workgroup: a VD_TILE x VD_TILE tile of cells (VD_TILE * VD_TILE = VD_WG).
#define VD_TILE 16
// A grid cell with no site yet (the seed grid is filled with it).
#define VD_NONE 0xFFFFFFFFu
// Words of the dual's counter buffer: triangles appended, appends past the capacity.
#define VD_COUNT_TRIS 0
#define VD_COUNT_OVERFLOW 1

// Square cells of side `cell` from (x0, y0): cell (cx, cy) is cy * width + cx.
struct VdGridPush {
  uint n;         // points (vd_seed) or the triangle capacity (vd_dual)
  uint width;
  uint height;
  uint step;      // vd_flood: the jump
  double x0;
  double y0;
  double cell;
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
