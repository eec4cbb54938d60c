// Legalisation, step 2: a candidate edge that won the claims of both its slots is flipped in place; both slots
// join the next queue (their four outer edges must be checked again). A candidate that lost keeps its slot in
// the next queue. The smallest key of the round always wins, so every round with a candidate flips something,
// and Lawson's argument (each flip lowers the lifted surface) bounds the number of flips.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "layout_cdt.h"
#include "common.glsl"
#include "subgroup_append.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
layout(std430, binding = 2) buffer CFlags { uint cflags[]; };
layout(std430, binding = 3) writeonly buffer Remap { uint remap[]; };
layout(std430, binding = 4) writeonly buffer Stamp { uint stamp[]; };
layout(std430, binding = 5) writeonly buffer Partner { uint partner[]; };
layout(std430, binding = 6) buffer QStamp { uint qstamp[]; };
layout(std430, binding = 7) readonly buffer Queue { uint queue[]; };
layout(std430, binding = 8) writeonly buffer Next { uint next_queue[]; };
layout(std430, binding = 9) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 10) readonly buffer Cand { uint cand[]; };
layout(std430, binding = 11) writeonly buffer Flips { uvec2 flips[]; };
layout(std430, binding = 12) buffer Ctl { uint ctl[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

#define CDT_FLIP_BUFFERS
#include "cdt_common.glsl"

void enqueue(uint t) {
  if (atomicExchange(qstamp[t], p.round + 1u) != p.round + 1u) {
    uint at;
    SUBGROUP_APPEND(at, ctl[CDT_CTL_NEXT]);
    next_queue[at] = t;
  }
}

void main() {
  uint j = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (j >= 3u * ctl[CDT_CTL_QUEUE]) return;
  if (cand[j] == 0u) return;
  uint t = queue[j / 3u], k = j % 3u;
  uint64_t key = cdt_claim_key(p.round, 0u, NBR(t, k));
  bool won = false;
  uint u = 0u, ku = 0u;
  if (claim[t] == key) {  // this slot is ours: its codes are stable
    uint code = nbrs(3u * t + k);
    u = NBR_TRI(code);
    ku = NBR_EDGE(code);
    won = claim[u] == key;
  }
  if (won) {
    cdt_flip(t, k, u, ku, p.round);
    uint at;
    SUBGROUP_APPEND(at, ctl[CDT_CTL_FLIPS]);
    flips[at] = uvec2(t, u);
    enqueue(t);
    enqueue(u);
  } else {
    enqueue(t);
  }
}
