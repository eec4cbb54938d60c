// Insertion round, optional step 0b (when enough points of the list became vertices): the points still to
// insert keep their (Morton) order in the next list, their loc codes with them:
// out[offsets[i]] = list[i], out_loc[offsets[i]] = loc[i] where flags[i] != 0 (offsets = exclusive scan of
// flags).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer List { uint list[]; };
layout(std430, binding = 1) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 3) writeonly buffer Out { uint out_list[]; };
layout(std430, binding = 4) readonly buffer Loc { uint loc[]; };
layout(std430, binding = 5) writeonly buffer OutLoc { uint out_loc[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  if (flags[i] == 0u) return;
  out_list[offsets[i]] = list[i];
  out_loc[offsets[i]] = loc[i];
}
