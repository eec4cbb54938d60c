// Legalisation, step 1: one invocation per edge of each queued slot. An edge is handled by its queued slot of
// smaller index. It is a candidate when it is not constrained, both its triangles are finite and the apex
// beyond it lies inside the circle of this triangle under CGAL's symbolically perturbed incircle (the test of
// Constrained_Delaunay_triangulation_2::is_flipable), which makes the constrained Delaunay triangulation unique.
// Such a quadrilateral is convex, so no orientation test is needed. Candidates claim both slots.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_cdt.h"
#include "common.glsl"
#include "predicates.glsl"
#include "cdt_common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 pts[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 3) readonly buffer CFlags { uint cflags[]; };
layout(std430, binding = 4) readonly buffer QStamp { uint qstamp[]; };
layout(std430, binding = 5) readonly buffer Queue { uint queue[]; };
layout(std430, binding = 6) buffer Claim { uint64_t claim[]; };
layout(std430, binding = 7) writeonly buffer Cand { uint cand[]; };
layout(std430, binding = 8) readonly buffer Ctl { uint ctl[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

void main() {
  uint j = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (j >= 3u * ctl[CDT_CTL_QUEUE]) return;
  uint t = queue[j / 3u], k = j % 3u;
  cand[j] = 0u;
  if (((cflags[t] >> k) & 1u) != 0u) return;
  uint code = nbrs(3u * t + k);
  uint u = NBR_TRI(code);
  if (qstamp[u] == p.round && u < t) return;
  uint a = verts(3u * t + k), b = verts(3u * t + cdt_next(k)), c = verts(3u * t + cdt_prev(k));
  uint d = verts(3u * u + NBR_EDGE(code));
  if (a == INF_VERTEX || b == INF_VERTEX || c == INF_VERTEX || d == INF_VERTEX) return;
  if (pred_incircle_perturbed(pts[a], pts[b], pts[c], pts[d]) <= 0) return;
  uint64_t key = cdt_claim_key(p.round, 0u, NBR(t, k));
  atomicMin(claim[t], key);
  atomicMin(claim[u], key);
  cand[j] = 1u;
}
