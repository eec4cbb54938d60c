// The TIN as the grid and contour passes read it (gpu/tin.hpp): vertices x, y, z and triangles in mesh order,
// at bindings 1 and 2 of every pass that includes this.
#ifndef CDTGPU_TIN_GLSL
#define CDTGPU_TIN_GLSL

layout(std430, binding = 1) readonly buffer Vertices { double xyz[]; };  // x, y, z per vertex
layout(std430, binding = 2) readonly buffer Triangles { uint tris[]; };  // 3 per triangle, mesh order

dvec3 vertex(uint v) { return dvec3(xyz[3u * v], xyz[3u * v + 1u], xyz[3u * v + 2u]); }

#endif
