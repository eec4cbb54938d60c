// What the contour passes share (gpu/contours.cpp, layout.h): the TIN and the levels, ascending.
#ifndef CDTGPU_CONTOUR_COMMON_GLSL
#define CDTGPU_CONTOUR_COMMON_GLSL

layout(std430, binding = 0) readonly buffer Levels { double levels[]; };
#include "tin.glsl"

// The first level index with levels[k] > z (num_levels if none).
uint first_above(double z, uint n) {
  uint lo = 0u, hi = n;
  while (lo < hi) {
    uint mid = (lo + hi) >> 1;
    if (levels[mid] > z) hi = mid; else lo = mid + 1u;
  }
  return lo;
}

#endif
