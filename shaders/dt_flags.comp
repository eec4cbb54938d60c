// Insertion round, step 0 when the list is compacted: flags[i] = 1 for a list position whose point is not a
// vertex yet (the scan's and dt_compact's input).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Loc { uint loc[]; };
layout(std430, binding = 1) writeonly buffer Flags { uint flags[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i < p.n) flags[i] = (loc[i] & DT_INSERTED) == 0u ? 1u : 0u;
}
