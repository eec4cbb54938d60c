// Flip pass, step 1b (indirect, over the exact list of step 1): the slots a floating-point filter could not
// decide are checked again with exact predicates, and request or settle like step 1. The list lives in the
// pick buffer, idle between insertion steps, which is left all DT_NONE again.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
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
layout(std430, binding = 6) buffer Exact { uint exact_list[]; };
layout(std430, binding = 7) buffer Counters { uint counters[]; };
layout(push_constant) uniform Push { DtFlipPush p; };

#define DT_EXACT 1
#define DT_CHECK
#define DT_CLAIMS
#include "dt_common.glsl"

void main() {
  uint j = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (j >= counters[DT_EXACT_FLIP]) return;
  if (j == 0u) counters[DT_EXACT_CHECKS] += counters[DT_EXACT_FLIP];
  uint i = exact_list[j];
  exact_list[j] = DT_NONE;
  uint entry = list[i];
  uint t = DT_ENTRY_SLOT(entry);
  uint k, uc;
  if (dt_check_slot(t, DT_ENTRY_MODE(entry), DT_ENTRY_EDGE(entry), k, uc) == 1) {
    list[i] = DT_ENTRY(t, DT_REQUEST, k);
    partner[t] = uc;
    uint64_t key = dt_claim_key(NBR(t, k));
    atomicMin(claim[t], key);
    atomicMin(claim[NBR_TRI(uc)], key);
  } else {
    list[i] = DT_NONE;
  }
}
