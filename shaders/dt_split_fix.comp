// Insertion round, step 5, over the bid list: each split repairs the outward edges of its new triangles
// (dt_fix_edge: through info[] when the neighbour was split too), marks its point as a vertex and lists its
// changed slots in flip list 0 with the edges to check: a 1->3 triangle only its outer edge, a 2->4 triangle
// its outer edge and, from t and X only, its half of the split edge (the spokes, the new edges at p, are
// locally Delaunay: docs/gpu-delaunay.md); an outer edge whose neighbour was split too is checked from the
// smaller slot only (dt_fix_edge). Every slot with a bid frees its pick word. The last workgroup sizes the first flip pass (over list 0) and empties list 1
// and the exact lists for their next use.
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
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
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
layout(std430, binding = 12) writeonly buffer Flip { uint flip_list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_APPEND
#define DT_CLAIMS
#define DT_FIX_EDGES
#define DT_LAST_GROUP
#define DT_RANKS
#include "dt_common.glsl"

#define DT_INSERT_FIX
#define DT_SPLIT_NUMBER(t, at) dt_rank(at)
#include "dt_insert.glsl"

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uvec4 e = i < counters[DT_BIDS] ? dt_fix_bid(bid_list[i]) : uvec4(DT_NONE);
  uint count = dt_pack_entries(e);
  dt_list_entries(dt_append_base(DT_COUNT_LIST0, count), count, e);
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) dt_round_listed(dt_count(DT_COUNT_LIST0));
}
