// Flip pass, step 1: every slot t of the current list looks for its first illegal edge (dt_check_slot,
// floating-point filters only). A request records its neighbour's code in partner[t] and claims t and the
// neighbour u with the priority NBR(t, k) (atomicMin of dt_claim_key): the smallest request wins both, so every
// pass flips something while requests remain. The entry becomes DT_ENTRY(t, DT_REQUEST, k), or DT_NONE when t
// is locally Delaunay. A slot a filter cannot decide goes to the exact list (kept in the idle pick buffer) for
// dt_flip_check_exact, which redoes its checks exactly; the last workgroup sizes that pass.
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
layout(std430, binding = 3) buffer Claim { uint64_t claim[]; };
layout(std430, binding = 4) writeonly buffer Partner { uint partner[]; };
layout(std430, binding = 5) buffer List { uint list[]; };
layout(std430, binding = 6) writeonly buffer Exact { uint exact_list[]; };
layout(std430, binding = 7) buffer Counters { uint counters[]; };
layout(std430, binding = 8) writeonly buffer Args { uint args[]; };
layout(push_constant) uniform Push { DtFlipPush p; };

#define DT_EXACT 0
#define DT_CHECK
#define DT_CLAIMS
#define DT_LAST_GROUP
#define DT_APPEND
#include "dt_common.glsl"

// Entry i: request or settle; returns true when a filter could not decide (the entry goes to the exact list).
bool check(uint i) {
  uint entry = list[i];
  uint t = DT_ENTRY_SLOT(entry);
  uint k, uc;
  int r = dt_check_slot(t, DT_ENTRY_MODE(entry), DT_ENTRY_EDGE(entry), k, uc);
  if (r == DT_UNDECIDED) {
    return true;
  } else if (r == 1) {
    list[i] = DT_ENTRY(t, DT_REQUEST, k);
    partner[t] = uc;
    uint64_t key = dt_claim_key(NBR(t, k));
    atomicMin(claim[t], key);
    atomicMin(claim[NBR_TRI(uc)], key);
  } else {
    list[i] = DT_NONE;
  }
  return false;
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  bool undecided = i < counters[DT_COUNT_LIST0 + p.src] && check(i);
  uint at = dt_append_base(DT_EXACT_FLIP, undecided ? 1u : 0u);
  if (undecided) exact_list[at] = i;
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) dt_write_args(DT_ARGS_FLIP, dt_count(DT_EXACT_FLIP));
}
