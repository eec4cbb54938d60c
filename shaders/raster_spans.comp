// One invocation per triangle: the grid rows (inside the band) and columns of cell centres its bounding box
// holds, and how many (triangle, row) work items raster_claim gets for it. Degenerate triangles get none (the
// CPU skips them too). spans[t] = (first row, first column, last column, 1 if counter-clockwise).
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "division.glsl"
#include "raster_common.glsl"

layout(local_size_x = RASTER_WG) in;
layout(std430, binding = 3) writeonly buffer Spans { uvec4 spans[]; };
layout(std430, binding = 4) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform Push { RasterPush p; };

// Smallest k with k * cell >= v, largest with k * cell <= v (core/raster.cpp's ceil_index, floor_index): the
// quotient's rounding is corrected with the same product the centres use. The quotient is the correctly
// rounded one, as on the CPU, so the corrections take a step or two (a coarse device quotient could be
// thousands of cells off at large coordinates).
double ceil_k(double v, double cell) {
  precise double k = ceil(div_rn(v, cell));
  for (int i = 0; i < 64 && k * cell < v; ++i) k += 1.0lf;
  for (int i = 0; i < 64 && (k - 1.0lf) * cell >= v; ++i) k -= 1.0lf;
  return k;
}
double floor_k(double v, double cell) {
  precise double k = floor(div_rn(v, cell));
  for (int i = 0; i < 64 && k * cell > v; ++i) k -= 1.0lf;
  for (int i = 0; i < 64 && (k + 1.0lf) * cell <= v; ++i) k += 1.0lf;
  return k;
}

void main() {
  uint t = linear_group_id() * RASTER_WG + gl_LocalInvocationIndex;
  if (t >= p.num_tris) return;
  dvec3 a = vertex(tris[3u * t]), b = vertex(tris[3u * t + 1u]), c = vertex(tris[3u * t + 2u]);
  counts[t] = 0u;
  spans[t] = uvec4(1u, 1u, 0u, 0u);
  int o = pred_orient2d(a.xy, b.xy, c.xy);
  if (o == 0) return;
  double cell = params[RASTER_CELL];
  double kx0 = params[RASTER_KX0], ky_top = params[RASTER_KY_TOP];
  // Columns and k_y of the centres inside the bounding box, clamped to the grid and the band.
  double x0 = max(ceil_k(min(a.x, min(b.x, c.x)), cell), kx0);
  double x1 = min(floor_k(max(a.x, max(b.x, c.x)), cell), kx0 + double(p.ncols - 1u));
  double y0 = max(ceil_k(min(a.y, min(b.y, c.y)), cell), ky_top - double(p.row0 + p.rows - 1u));
  double y1 = min(floor_k(max(a.y, max(b.y, c.y)), cell), ky_top - double(p.row0));
  if (x0 > x1 || y0 > y1) return;
  uint r0 = uint(ky_top - y1), r1 = uint(ky_top - y0);
  spans[t] = uvec4(r0, uint(x0 - kx0), uint(x1 - kx0), o > 0 ? 1u : 0u);
  counts[t] = r1 - r0 + 1u;
}
