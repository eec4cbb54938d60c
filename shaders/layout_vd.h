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
// Words of the counter buffer: triangles appended, appends past the capacity, points blamed for a triangle
// surely not counter-clockwise (vd_dual), cells left empty by the last flood pass (vd_flood).
#define VD_COUNT_TRIS 0
#define VD_COUNT_OVERFLOW 1
#define VD_COUNT_EMPTY 2
#define VD_COUNT_BLAMED 3
#define VD_COUNT_UNDECIDED 4  // triangles whose orientation the dual's filter left to the host
#define VD_COUNT_WORDS 5

// Square cells of side `cell` from (x0, y0): cell (cx, cy) is cy * width + cx.
struct VdGridPush {
  uint n;         // points (vd_seed), the triangle capacity (vd_dual), 1 on the last pass (vd_flood)
  uint width;
  uint height;
  uint step;      // vd_flood: the jump; vd_seed: 1 in a repair (seed the emptied cells only)
  double x0;
  double y0;
  double cell;
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
