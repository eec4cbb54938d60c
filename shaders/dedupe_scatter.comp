// Vertex numbers from the scan of the flags: every input point learns its vertex (map), every vertex its
// coordinates and its first occurrence (the stable sort puts the lowest input index first in each run).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dedupe.h"
#include "common.glsl"

layout(local_size_x = DEDUPE_WG) in;
layout(std430, binding = 0) readonly buffer Points { uvec4 xy_bits[]; };  // one point: x and y
layout(std430, binding = 1) readonly buffer Index { uint idx[]; };
layout(std430, binding = 2) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 3) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 4) writeonly buffer Unique { uvec4 unique_xy[]; };
layout(std430, binding = 5) writeonly buffer Map { uint map[]; };
layout(std430, binding = 6) writeonly buffer First { uint first[]; };
layout(std430, binding = 7) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { DedupePush p; };

void main() {
  uint i = linear_group_id() * DEDUPE_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  uint v = offsets[i] + flags[i] - 1u;
  uint j = idx[i];
  map[j] = v;
  if (flags[i] != 0u) {
    unique_xy[v] = xy_bits[j];
    first[v] = j;
  }
  if (i == p.n - 1u) count[0] = v + 1u;
}
