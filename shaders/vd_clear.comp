// Voronoi first stage, a repair's start: the last flood's grid with the cells of demoted sites emptied, so the
// next flood only has to fill those holes (vd_seed reseeds the points in them, a few short jumps do the rest)
// instead of flooding the whole grid again.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Demoted { uint demoted[]; };
layout(std430, binding = 1) readonly buffer Src { uint src[]; };
layout(std430, binding = 2) writeonly buffer Dst { uint dst[]; };
layout(push_constant) uniform Push { VdGridPush p; };

void main() {
  uint c = linear_group_id() * VD_WG + gl_LocalInvocationIndex;
  if (c >= p.width * p.height) return;
  uint s = src[c];
  dst[c] = s != VD_NONE && demoted[s] != 0u ? VD_NONE : s;
}
