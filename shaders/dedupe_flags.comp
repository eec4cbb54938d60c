// After the sort by (x, y): flags[i] = 1 where sorted point i differs from sorted point i - 1 (a new vertex).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dedupe.h"
#include "common.glsl"
#include "dedupe_common.glsl"

layout(local_size_x = DEDUPE_WG) in;
layout(std430, binding = 0) readonly buffer Points { uvec2 xy_bits[]; };
layout(std430, binding = 1) readonly buffer Index { uint idx[]; };
layout(std430, binding = 2) writeonly buffer Flags { uint flags[]; };
layout(push_constant) uniform Push { DedupePush p; };

void main() {
  uint i = linear_group_id() * DEDUPE_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  bool first = i == 0u;
  if (!first) {
    uint a = idx[i], b = idx[i - 1u];
    first = order_key(xy_bits[2u * a]) != order_key(xy_bits[2u * b]) ||
            order_key(xy_bits[2u * a + 1u]) != order_key(xy_bits[2u * b + 1u]);
  }
  flags[i] = first ? 1u : 0u;
}
