// One invocation per triangle of the chunk: the levels it crosses, lowest z < level <= highest z (core/
// contours.cpp's rule), as (first level index, count). Every such level gives exactly one segment.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "contour_common.glsl"

layout(local_size_x = CONTOUR_WG) in;
layout(std430, binding = 3) writeonly buffer First { uint first[]; };
layout(std430, binding = 4) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform Push { ContourPush p; };

void main() {
  uint i = linear_group_id() * CONTOUR_WG + gl_LocalInvocationIndex;
  if (i >= p.num_tris) return;
  uint t = p.tri0 + i;
  double za = xyz[3u * tris[3u * t] + 2u], zb = xyz[3u * tris[3u * t + 1u] + 2u];
  double zc = xyz[3u * tris[3u * t + 2u] + 2u];
  double lo = min(za, min(zb, zc)), hi = max(za, max(zb, zc));
  uint k0 = first_above(lo, p.num_levels);  // levels above the lowest vertex
  uint k1 = first_above(hi, p.num_levels);  // ... and those at or below the highest: [k0, k1)
  first[i] = k0;
  counts[i] = k1 > k0 ? k1 - k0 : 0u;
}
