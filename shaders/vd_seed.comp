// Voronoi first stage, step 1 (discretise): every point not demoted claims the grid cell it lies in; the
// smallest build number wins, so the seed grid is the same on every run. The others of a cell are "lost"
// points, inserted later by the rounds. Every point's position in cell units (float, from the grid's corner)
// goes beside it for the flood, which then reads 8 bytes per candidate instead of 16 and no doubles. In a
// repair (p.step = 1) only the cells vd_clear emptied are seeded: the rest keep the last flood's sites.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) readonly buffer Demoted { uint demoted[]; };
layout(std430, binding = 2) buffer Grid { uint grid[]; };
layout(std430, binding = 3) writeonly buffer CellOf { uint cell_of[]; };
layout(std430, binding = 4) writeonly buffer Sites { vec2 site[]; };
layout(std430, binding = 5) readonly buffer Last { uint last[]; };  // a repair: the last flood's grid
layout(push_constant) uniform Push { VdGridPush p; };
#include "vd_common.glsl"

void main() {
  uint i = linear_group_id() * VD_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  dvec2 q = xy[i];
  uint c = vd_cell(q);
  cell_of[i] = c;
  site[i] = vec2((q - dvec2(p.x0, p.y0)) / p.cell);
  if (demoted[i] != 0u) return;
  if (p.step != 0u) {
    uint s = last[c];
    if (s == VD_NONE || demoted[s] == 0u) return;
  }
  atomicMin(grid[c], i);
}
