// Canonical order by buckets, step 3, one invocation per vertex a: its bucket (the triangles whose smallest
// vertex is a, about two on average) sorted by b in place, an insertion sort. Directed edges a->b are unique,
// so the order is total. A bucket above CANONICAL_BUCKET_MAX (a vertex at the centre of a huge fan) sets
// count[1]: the host then sorts everything with the radix sort instead, so no invocation runs long.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CANONICAL_WG) in;
layout(std430, binding = 0) readonly buffer Buckets { uint bucket[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) restrict readonly buffer TrianglesAt { TriWords tris_at; };
#define tris(i) TRI_WORD(TriWords, tris_at, i)
layout(std430, binding = 3) buffer Count { uint count[]; };
layout(push_constant) uniform Push { CanonicalKeysPush p; };

void main() {
  uint a = linear_group_id() * CANONICAL_WG + gl_LocalInvocationIndex;
  if (a >= p.num_points) return;
  uint n = bucket[a];
  if (n < 2u) return;
  if (n > CANONICAL_BUCKET_MAX) {
    count[1] = 1u;
    return;
  }
  uint base = offsets[a];
  for (uint i = 1u; i < n; ++i) {
    uint b = tris(3u * (base + i) + 1u), c = tris(3u * (base + i) + 2u);
    uint j = i;
    for (; j > 0u && tris(3u * (base + j - 1u) + 1u) > b; --j) {
      tris(3u * (base + j) + 1u) = tris(3u * (base + j - 1u) + 1u);
      tris(3u * (base + j) + 2u) = tris(3u * (base + j - 1u) + 2u);
    }
    tris(3u * (base + j) + 1u) = b;
    tris(3u * (base + j) + 2u) = c;
  }
}
