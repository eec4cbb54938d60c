// Insertion round, step 5, over the bid list: each split repairs the outward edges of its new triangles
// (dt_fix_edge: through info[] when the neighbour was split too) and marks its point as a vertex; every slot
// with a bid frees its pick word. The last workgroup sizes the first flip pass (over list 0) and empties list 1
// and the exact lists for their next use.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Verts { uint verts[]; };
layout(std430, binding = 1) buffer Nbrs { uint nbrs[]; };
layout(std430, binding = 2) buffer Loc { uint loc[]; };
layout(std430, binding = 3) buffer Pick { uint pickw[]; };
layout(std430, binding = 4) readonly buffer Granted { uint granted[]; };
layout(std430, binding = 5) readonly buffer Info { uint info[]; };
layout(std430, binding = 6) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 7) buffer Counters { uint counters[]; };
layout(std430, binding = 8) writeonly buffer Args { uint args[]; };
layout(std430, binding = 9) readonly buffer Ranks { uint ranks[]; };
layout(std430, binding = 10) readonly buffer Bids { uint bid_list[]; };
layout(std430, binding = 11) readonly buffer GrantedAt { uint granted_at[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_CLAIMS
#define DT_FIX_EDGES
#define DT_LAST_GROUP
#define DT_RANKS
#include "dt_common.glsl"

void fix(uint t) {
  uint at = pickw[2u * t], sc = pickw[2u * t + 1u];
  pickw[2u * t] = DT_NONE;
  pickw[2u * t + 1u] = DT_NONE;
  if (!dt_granted(t)) return;
  uint k = NBR_EDGE(loc[at]);
  loc[at] = DT_INSERTED | NBR(t, DT_INSIDE);  // t has the new vertex as a corner
  uint X = p.base + 2u * dt_rank(at);
  if (k == DT_INSIDE) {
    dt_fix_edge(t, 0u);
    dt_fix_edge(X, 1u);
    dt_fix_edge(X + 1u, 2u);
  } else {
    uint s = NBR_TRI(sc), j = NBR_EDGE(sc);
    dt_fix_edge(t, dt_prev(k));
    dt_fix_edge(X, dt_next(k));
    dt_fix_edge(s, dt_prev(j));
    dt_fix_edge(X + 1u, dt_next(j));
  }
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i < counters[DT_BIDS]) fix(bid_list[i]);
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) {
    uint n = dt_count(DT_COUNT_LIST0);
    dt_write_list_args(0u, n);
    counters[DT_COUNT_LIST1] = 0u;
    counters[DT_BIDS] = 0u;  // the bid list is done with
    counters[DT_EXACT_RELOC] = 0u;
    counters[DT_EXACT_FLIP] = 0u;
    if (n > 0u) counters[DT_FLIP_PASSES] += 1u;
  }
}
