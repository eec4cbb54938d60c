// Delaunay start, after the Morton sort: loc is kept per list position, so it is set now that the list is
// sorted: the first triangle's corners are vertices, every other point is "somewhere in slot 0".
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer List { uint list[]; };
layout(std430, binding = 1) writeonly buffer Loc { uint loc[]; };
layout(push_constant) uniform Push { DtInitPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  uint pt = list[i];
  loc[i] = pt == p.a || pt == p.b || pt == p.c ? DT_INSERTED : NBR(0u, DT_INSIDE);
}
