// Canonical order by buckets, step 2, one invocation per slot: a finite triangle goes to its place in a's
// bucket (offset from the scan of the bucket sizes, plus its rank), as the host's (a, b, c) layout.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CANONICAL_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) readonly buffer Rank { uint rank[]; };
layout(std430, binding = 3) restrict readonly buffer TrianglesAt { TriWordsW tris_at; };
#define tris(i) TRI_WORD(TriWordsW, tris_at, i)
layout(push_constant) uniform Push { CanonicalKeysPush p; };

#include "canonical_common.glsl"

void main() {
  uint t = linear_group_id() * CANONICAL_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots) return;
  uvec3 tri;
  if (!canonical_triangle(t, tri)) return;
  uint at = offsets[tri.x] + rank[t];
  tris(3u * at) = tri.x;
  tris(3u * at + 1u) = tri.y;
  tris(3u * at + 2u) = tri.z;
}
