// Insertion round, step 1b (indirect, over the exact list of step 1): the walks a floating-point filter could
// not finish resume from where they stopped with exact predicates, then bid like step 1. The last workgroup
// sizes the per-slot steps over the bid list.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 3) buffer Loc { uint loc[]; };
layout(std430, binding = 4) buffer Pick { uint64_t pick[]; };
layout(std430, binding = 5) readonly buffer Exact { uint exact_list[]; };
layout(std430, binding = 6) buffer Counters { uint counters[]; };
layout(std430, binding = 7) writeonly buffer Args { uint args[]; };
layout(std430, binding = 8) writeonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 9) readonly buffer List { uint list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_EXACT 1
#define DT_WALK
#define DT_LAST_GROUP
#define DT_APPEND
#include "dt_common.glsl"

// Exact-list entry i: its walk and bid; returns the slot when this was the slot's first bid, else DT_NONE.
uint relocate(uint i) {
  if (i == 0u) counters[DT_EXACT_WALKS] += counters[DT_EXACT_RELOC];
  uint at = exact_list[i], pt = list[at];
  dvec2 q = xy[pt];
  bool undecided;
  uint code = dt_walk(NBR_TRI(loc[at]), q, p.max_steps, undecided);
  loc[at] = code;
  uint t = NBR_TRI(code);
  return dt_bid(t, (uint64_t(dt_bid_key(code, q)) << 32) | uint64_t(at)) == 1u ? t : DT_NONE;
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint slot = i < counters[DT_EXACT_RELOC] ? relocate(i) : DT_NONE;
  uint listed = dt_append_base(DT_BIDS, slot != DT_NONE ? 1u : 0u);
  if (slot != DT_NONE) bid_list[listed] = slot;
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) dt_write_args(DT_ARGS_BIDS, dt_count(DT_BIDS));
}
