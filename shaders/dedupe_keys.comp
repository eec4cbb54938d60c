// Sort keys of one coordinate: keys[i] = order_key(coordinate of point j), j = i or idx[i] (see DedupeKeysPush).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dedupe.h"
#include "common.glsl"
#include "dedupe_common.glsl"

layout(local_size_x = DEDUPE_WG) in;
layout(std430, binding = 0) readonly buffer Points { uvec2 xy_bits[]; };  // x, y per point
layout(std430, binding = 1) writeonly buffer Keys { uvec2 keys[]; };
layout(std430, binding = 2) buffer Index { uint idx[]; };
layout(push_constant) uniform Push { DedupeKeysPush p; };

void main() {
  uint i = linear_group_id() * DEDUPE_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  uint j = i;
  if (p.gather != 0u)
    j = idx[i];
  else
    idx[i] = i;
  keys[i] = order_key(xy_bits[2u * j + p.coord]);
}
