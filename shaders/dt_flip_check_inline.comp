// Flip pass, step 1, for GPUs (the build picks it on every device but a CPU one): dt_flip_check with the
// exact stage inline, so no exact list and no second pass. Every slot t of the current list looks for its
// first illegal edge (dt_check_slot, exact). A request records its neighbour's code in partner[t] and claims t and the
// neighbour u with the priority NBR(t, k) (atomicMin of dt_claim_key): the smallest request wins both, so every
// pass flips something while requests remain. The entry becomes DT_ENTRY(t, DT_REQUEST, k), or DT_NONE when t
// is locally Delaunay. Slots that needed the exact stage are counted (DT_EXACT_CHECKS): the host goes back to
// the filter + exact pass pair when they are many. Same bindings as dt_flip_check; the exact list and its
// arguments stay unused.
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
layout(std430, binding = 6) writeonly buffer Exact { uint exact_list[]; };
layout(std430, binding = 7) buffer Counters { uint counters[]; };
layout(std430, binding = 8) writeonly buffer Args { uint args[]; };
layout(push_constant) uniform Push { DtFlipPush p; };

#define DT_EXACT 1
#define DT_CHECK
#define DT_CLAIMS
#include "dt_common.glsl"

void check(uint i) {
  list[i] = dt_request(list[i]);
  if (dt_used_exact) atomicAdd(counters[DT_EXACT_CHECKS], 1u);
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i < counters[DT_COUNT_LIST0 + p.src]) check(i);
}
