// Insertion round, step 3, over the bid list: slot t's split is granted when its point won every claim it made
// (dt_grant_bid); granted splits set their slot's bit and their point's list-position bit (DT_RANKS). dt_rank and a scan then
// number the splits in list (Morton) order, two new slots each.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Pick { uint pickw[]; };
layout(std430, binding = 1) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 2) buffer Granted { uint granted[]; };  // cleared before this step
layout(std430, binding = 3) readonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 4) readonly buffer Counters { uint counters[]; };
layout(std430, binding = 5) buffer GrantedAt { uint granted_at[]; };  // by the winner's list position
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_CLAIMS
#include "dt_common.glsl"
#define DT_INSERT_GRANT
#include "dt_insert.glsl"

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= counters[DT_BIDS]) return;
  uint t = bid_list[i];
  if (dt_grant_bid(t)) {
    uint at = pickw[2u * t];
    atomicOr(granted[t >> 5u], 1u << (t & 31u));
    atomicOr(granted_at[at >> 5u], 1u << (at & 31u));
  }
}
