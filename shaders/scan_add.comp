// Second half of a multi-level scan: adds the scanned block total offsets[b] to every element of block b.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"

layout(local_size_x = SCAN_WG) in;
layout(std430, binding = 0) buffer Data { uint data[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(push_constant) uniform Push { ScanAddPush p; };

void main() {
  uint block = linear_group_id();
  uint base = block * SCAN_BLOCK;
  if (base >= p.n) return;
  uint add = offsets[block];
  for (uint k = 0; k < SCAN_ITEMS; ++k) {
    uint g = base + k * SCAN_WG + gl_LocalInvocationIndex;
    if (g < p.n) data[g] += add;
  }
}
