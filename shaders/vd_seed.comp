// Voronoi first stage, step 1 (discretise): every point not demoted claims the grid cell it lies in; the
// smallest build number wins, so the seed grid is the same on every run. The others of a cell are "lost"
// points, inserted later by the rounds.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) readonly buffer Demoted { uint demoted[]; };
layout(std430, binding = 2) buffer Grid { uint grid[]; };
layout(std430, binding = 3) writeonly buffer CellOf { uint cell_of[]; };
layout(push_constant) uniform Push { VdGridPush p; };
#include "vd_common.glsl"

void main() {
  uint i = linear_group_id() * VD_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  uint c = vd_cell(xy[i]);
  cell_of[i] = c;
  if (demoted[i] == 0u) atomicMin(grid[c], i);
}
