// Adaptive parallel flipping, step 2: every candidate row that won the claims of both its slots flips its edge
// in place (cdt_common.glsl) and appends the two slots to the flip list for cdt_fix.comp. Winners own disjoint
// slot pairs, and a winner reads only its own two slots, so the flips of one round do not race.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "layout_cdt.h"
#include "common.glsl"
#include "subgroup_append.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
layout(std430, binding = 2) readonly buffer Table { CdtCross table[]; };
layout(std430, binding = 3) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 4) buffer CFlags { uint cflags[]; };
layout(std430, binding = 5) writeonly buffer Remap { uint remap[]; };
layout(std430, binding = 6) writeonly buffer Stamp { uint stamp[]; };
layout(std430, binding = 7) writeonly buffer Partner { uint partner[]; };
layout(std430, binding = 8) writeonly buffer Flips { uvec2 flips[]; };
layout(std430, binding = 9) buffer Ctl { uint ctl[]; };
layout(std430, binding = 10) readonly buffer First { uint64_t first_row[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

#define CDT_FLIP_BUFFERS
#include "cdt_common.glsl"

void main() {
  uint g = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (g >= ctl[CDT_CTL_TOTAL]) return;
  uint flag = table[g].flag;
  if (flag == 0u) return;
  uint64_t key = cdt_claim_key(p.round, flag - 1u, g);
  if (p.one_per_constraint != 0u && first_row[table[g].cons] != key) return;
  uint t1 = NBR_TRI(table[g].edge), k1 = NBR_EDGE(table[g].edge);
  if (claim[t1] != key) return;
  uint code2 = nbrs(3u * t1 + k1);
  uint t2 = NBR_TRI(code2), k2 = NBR_EDGE(code2);
  if (claim[t2] != key) return;
  cdt_flip(t1, k1, t2, k2, p.round);
  uint at;
  SUBGROUP_APPEND(at, ctl[CDT_CTL_FLIPS]);
  flips[at] = uvec2(t1, t2);
}
