// After the sort: the first count[0] slots (the finite triangles, in canonical order) written as (a, b, c)
// vertex triples, the host's Triangle layout, so the download is one copy with no conversion on the host.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CANONICAL_WG) in;
layout(std430, binding = 0) readonly buffer Keys { uvec2 keys[]; };  // (a << p.shift) | b, as canonical_keys
layout(std430, binding = 1) readonly buffer Payload { uint payload[]; };
layout(std430, binding = 2) restrict readonly buffer TrianglesAt { TriWordsW tris_at; };
#define tris(i) TRI_WORD(TriWordsW, tris_at, i)
layout(std430, binding = 3) readonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { CanonicalKeysPush p; };

void main() {
  uint t = linear_group_id() * CANONICAL_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots || t >= count[0]) return;
  uvec2 k = keys[t];
  tris(3u * t) = (k.y << (32u - p.shift)) | (k.x >> p.shift);
  tris(3u * t + 1u) = k.x & ((1u << p.shift) - 1u);
  tris(3u * t + 2u) = payload[t];
}
