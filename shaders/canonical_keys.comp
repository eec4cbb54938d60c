// Sort key of each slot for the canonical triangle order: a finite triangle rotated to start at its smallest
// vertex a, (a, b, c) counter-clockwise, gets key (a << 32 | b) and payload c. The directed edge a->b lies in one
// triangle only, so finite keys are unique and sorting them is the canonical order. The key packs a and b into
// p.shift bits each ((a << shift) | b, shift = the bit width of num_points): fewer radix passes than a 32-bit
// b field. Infinite slots get a = num_points, after every finite key; count[0] counts the finite slots (one
// atomic per subgroup).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout.h"
#include "common.glsl"
#include "subgroup_append.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CANONICAL_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 1) writeonly buffer Keys { uvec2 keys[]; };  // (low word, high word)
layout(push_constant) uniform Push { CanonicalKeysPush p; };

// (a << p.shift) | b as (low word, high word); 0 < shift < 32.
uvec2 pack(uint a, uint b) { return uvec2((a << p.shift) | b, a >> (32u - p.shift)); }
layout(std430, binding = 2) writeonly buffer Payload { uint payload[]; };
layout(std430, binding = 3) buffer Count { uint count[]; };

#include "canonical_common.glsl"

void main() {
  uint t = linear_group_id() * CANONICAL_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots) return;
  uvec3 tri;
  if (!canonical_triangle(t, tri)) {
    keys[t] = pack(p.num_points, 0u);
    payload[t] = 0u;
    return;
  }
  keys[t] = pack(tri.x, tri.y);
  payload[t] = tri.z;
  SUBGROUP_ADD(count[0], 1u);
}
