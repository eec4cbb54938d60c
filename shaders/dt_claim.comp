// Insertion round, step 2, over the bid list (the slots with a bid): the point that won slot t's bid claims
// what its split rewrites (dt_claim_bid).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 1) readonly buffer Loc { uint loc[]; };
layout(std430, binding = 2) buffer Pick { uint pickw[]; };  // pick[t] as words: [2t] point, [2t+1] key
layout(std430, binding = 3) buffer Claim { uint64_t claim[]; };
layout(std430, binding = 4) readonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 5) readonly buffer Counters { uint counters[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_CLAIMS
#include "dt_common.glsl"
#define DT_INSERT_CLAIM
#include "dt_insert.glsl"

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i < counters[DT_BIDS]) dt_claim_bid(bid_list[i]);
}
