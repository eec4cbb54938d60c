// Canonical order by buckets, step 1, one invocation per slot: a finite triangle (a, b, c) in canonical form
// counts itself in a's bucket and keeps its rank there (rank order depends on scheduling; step 3 sorts each
// bucket by b, so the result does not). count[0] counts the finite slots (one atomic per subgroup).
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
layout(std430, binding = 1) buffer Buckets { uint bucket[]; };  // per vertex, zeroed before
layout(std430, binding = 2) writeonly buffer Rank { uint rank[]; };
layout(std430, binding = 3) buffer Count { uint count[]; };
layout(push_constant) uniform Push { CanonicalKeysPush p; };

#include "canonical_common.glsl"

void main() {
  uint t = linear_group_id() * CANONICAL_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots) return;
  uvec3 tri;
  if (!canonical_triangle(t, tri)) return;
  rank[t] = atomicAdd(bucket[tri.x], 1u);
  SUBGROUP_ADD(count[0], 1u);
}
