// Insertion round, step 3b, over the words of the granted list-position bits and one more: ranks[w] = set bits of word w
// (0 for the extra word); the exclusive scan that follows makes it the number of granted slots before word w,
// and its last entry the number of splits.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer GrantedAt { uint granted_at[]; };
layout(std430, binding = 1) writeonly buffer Ranks { uint ranks[]; };
layout(push_constant) uniform Push { DtRoundPush p; };  // n: words

void main() {
  uint w = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (w <= p.n) ranks[w] = w < p.n ? bitCount(granted_at[w]) : 0u;
}
