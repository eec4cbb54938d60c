// What the raster passes share (gpu/raster.cpp, layout.h): the grid numbers, the TIN's vertices and triangles,
// cell-centre coordinates, exactly as core/raster.cpp computes them.
#ifndef CDTGPU_RASTER_COMMON_GLSL
#define CDTGPU_RASTER_COMMON_GLSL

layout(std430, binding = 0) readonly buffer Params { double params[]; };
#include "tin.glsl"

// Centres: ((kx0 + col) * cell, (ky_top - row) * cell). The integer sum is exact in double (|k| < 2^53), so
// this is the CPU's double(ix0 + col) * cell.
double centre_x(uint col) {
  precise double k = params[RASTER_KX0] + double(col);
  precise double x = k * params[RASTER_CELL];
  return x;
}
double centre_y(uint row) {
  precise double k = params[RASTER_KY_TOP] - double(row);
  precise double y = k * params[RASTER_CELL];
  return y;
}

#endif
