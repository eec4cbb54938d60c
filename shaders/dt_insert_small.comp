// Insertion round, steps 2-5 in one workgroup, while at most DT_SMALL_SLOTS slots are in use (the first rounds
// of a build): claim, grant, number, split and fix (shaders/dt_insert.glsl, the bodies of dt_claim, dt_grant,
// dt_split and dt_split_fix) separated by workgroup barriers instead of five dependent dispatches (each ~5-10 us
// on the H100 however few its bids). A workgroup of DT_SMALL_WG invocations, one bid each: a step is a chain of
// dependent loads per bid, so bids taken in turn add up (H100: 1881 bids took 97 us with 256 invocations and 78
// with 1024, against ~55 us for the five dispatches; 644 bids 34 us against ~55). The splits are numbered in slot order (the granted bits are at most 64
// words here; the dispatched steps number them in list order for locality, which so few slots do not need).
// The round's slot bits are cleared at the end and no list-position bits are set, so both copies of the bit
// sets stay clear for the rounds that follow (DelaunayBuilder::bit_set). The buffers are coherent: each step
// reads the others' writes across barriers.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_SMALL_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsC verts_at; };
#define verts(i) TRI_WORD(TriWordsC, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWordsC nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsC, nbrs_at, i)
layout(std430, binding = 2) coherent buffer Loc { uint loc[]; };
layout(std430, binding = 3) coherent buffer Pick { uint pickw[]; };
layout(std430, binding = 4) coherent buffer Claim { uint64_t claim[]; };
layout(std430, binding = 5) readonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 6) buffer Counters { uint counters[]; };
layout(std430, binding = 7) writeonly buffer Args { uint args[]; };
layout(std430, binding = 8) coherent buffer Granted { uint granted[]; };
layout(std430, binding = 9) coherent buffer Info { uint info[]; };  // the partner buffer, idle now
layout(std430, binding = 10) writeonly buffer Flip { uint flip_list[]; };
layout(std430, binding = 11) readonly buffer List { uint list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };  // base: slots in use, at most DT_SMALL_SLOTS

#define DT_CLAIMS
#define DT_GRANTED
#define DT_FIX_EDGES
#define DT_LAST_GROUP
#include "dt_common.glsl"

shared uint word_rank[DT_SMALL_SLOTS / 32u];  // granted slots before each word of the granted bits
shared uint listed, winners;

uint slot_rank(uint t) { return word_rank[t >> 5u] + bitCount(granted[t >> 5u] & ((1u << (t & 31u)) - 1u)); }

#define DT_SPLIT_NUMBER(t, at) slot_rank(t)
#define DT_INSERT_CLAIM
#define DT_INSERT_GRANT
#define DT_INSERT_SPLIT
#define DT_INSERT_FIX
#include "dt_insert.glsl"

void step_barrier() {
  memoryBarrierBuffer();
  barrier();
}

void main() {
  uint lid = gl_LocalInvocationIndex, n = counters[DT_BIDS], words = (p.base + 31u) / 32u;
  if (lid == 0u) listed = 0u;
  for (uint i = lid; i < n; i += DT_SMALL_WG) dt_claim_bid(bid_list[i]);
  step_barrier();
  for (uint i = lid; i < n; i += DT_SMALL_WG) {
    uint t = bid_list[i];
    if (dt_grant_bid(t)) atomicOr(granted[t >> 5u], 1u << (t & 31u));
  }
  step_barrier();
  if (lid < words) word_rank[lid] = bitCount(granted[lid]);
  barrier();
  if (lid == 0u) {
    uint sum = 0u;
    for (uint w = 0u; w < words; ++w) {
      uint c = word_rank[w];
      word_rank[w] = sum;
      sum += c;
    }
    winners = sum;
  }
  barrier();
  for (uint i = lid; i < n; i += DT_SMALL_WG) dt_split_bid(bid_list[i]);
  step_barrier();
  for (uint i = lid; i < n; i += DT_SMALL_WG) {
    uvec4 e = dt_fix_bid(bid_list[i]);
    uint count = dt_pack_entries(e);
    if (count > 0u) dt_list_entries(atomicAdd(listed, count), count, e);
  }
  step_barrier();
  if (lid < words) granted[lid] = 0u;
  if (lid == 0u) {
    counters[DT_WINNERS] = winners;
    counters[DT_COUNT_LIST0] = listed;
    dt_round_listed(listed);
  }
}
