// Insertion round, step 4, over the bid list: every granted point splits its slot(s); new slots come from the
// rank of the split's point in the list (Morton order), two per split, X = base + 2 * dt_rank(position). Edge indices are kept, so an edge that
// leaves a slot keeps its index and info[] says where it went (dt_fix_edge reads it in the next step):
//   1->3, p inside t = (v0, v1, v2): t = (p, v1, v2), X = (v0, p, v2), X+1 = (v0, v1, p); old edge k now lives
//     in triangle k, index k (info[t] = NBR(X, 3)). Internal edges: triangle a's edge b meets triangle b's edge a.
//   2->4, p on edge i of t = (c@i, a@i+1, b@i+2), whose neighbour s = (d@j, b@j+1, a@j+2) (possibly infinite):
//     t = (c, a, p), X = (c, p, b) [t's edge i+1 moved there, info[t] = NBR(X, i+1)],
//     s = (d, b, p), X+1 = (d, p, a) [s's edge j+1 moved there, info[s] = NBR(X+1, j+1)].
// dt_split_fix then lists the changed slots for the flip passes.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
layout(std430, binding = 2) readonly buffer Loc { uint loc[]; };
layout(std430, binding = 3) readonly buffer Pick { uint pickw[]; };
layout(std430, binding = 4) readonly buffer Granted { uint granted[]; };
layout(std430, binding = 5) writeonly buffer Info { uint info[]; };  // the partner buffer, idle now
layout(std430, binding = 6) buffer Counters { uint counters[]; };
layout(std430, binding = 7) readonly buffer Ranks { uint ranks[]; };
layout(std430, binding = 8) readonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 9) readonly buffer GrantedAt { uint granted_at[]; };
layout(std430, binding = 10) readonly buffer List { uint list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_RANKS
#include "dt_common.glsl"

#define DT_INSERT_SPLIT
#define DT_SPLIT_NUMBER(t, at) dt_rank(at)
#include "dt_insert.glsl"

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i == 0u) counters[DT_WINNERS] = dt_split_count();
  if (i < counters[DT_BIDS]) dt_split_bid(bid_list[i]);
}
