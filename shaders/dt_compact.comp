// Insertion round, optional step after dt_relocate (when enough points of the list became vertices): the points
// still to insert keep their (Morton) order in the next list:
// out[offsets[i]] = list[i] where flags[i] != 0 (offsets = exclusive scan of flags).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer List { uint list[]; };
layout(std430, binding = 1) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 3) writeonly buffer Out { uint out_list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  if (flags[i] != 0u) out_list[offsets[i]] = list[i];
}
