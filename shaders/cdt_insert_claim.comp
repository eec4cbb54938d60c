// Adaptive parallel flipping, step 1: one invocation per row of the intersected-edge table. The row's edge e_i
// (between T_{i-1} and T_i) is a candidate when constraint c owns both triangles (no constraint of smaller index
// crosses them, so the flip cannot disturb a constraint of higher priority) and the quadrilateral is strictly
// convex (both new triangles counter-clockwise). The paper's Fig. 7 cases: convex and the new edge no longer
// crosses c (the apexes of T_{i-1} and T_i on the same side of c, or one is an endpoint of c): claims in class 0;
// convex and the new edge still crosses c: class 1, so it yields to a flip that removes a crossing; concave:
// not a candidate, waits for its neighbours to change. Candidates claim both slots; cdt_insert_flip flips the
// ones that won both. (Ablations: one_per_constraint, only the candidate with the constraint's smallest key flips;
// domain = 0, no owner check, conflicts are settled by the slot claims alone.)
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_cdt.h"
#include "common.glsl"
#include "predicates.glsl"
#include "cdt_common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 pts[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 3) buffer Table { CdtCross table[]; };
layout(std430, binding = 4) readonly buffer Owner { uint64_t owner[]; };
layout(std430, binding = 5) buffer Claim { uint64_t claim[]; };
layout(std430, binding = 6) buffer Ctl { uint ctl[]; };
layout(std430, binding = 7) buffer First { uint64_t first_row[]; };  // per constraint (one_per_constraint)
layout(std430, binding = 8) readonly buffer CFlags { uint cflags[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

void main() {
  uint g = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (g >= ctl[CDT_CTL_TOTAL]) return;
  CdtCross e = table[g];
  if (e.cons == CDT_NEVER) return;  // an empty row of the fixed-slot layout
  uint t1 = NBR_TRI(e.edge), k1 = NBR_EDGE(e.edge);
  uint code2 = nbrs(3u * t1 + k1);
  uint t2 = NBR_TRI(code2), k2 = NBR_EDGE(code2);
  uint64_t okey = cdt_owner_key(p.round, e.cons);
  if (p.domain != 0u && (owner[t1] != okey || owner[t2] != okey)) return;
  // A constraint is marked when its count walk (or cavity) makes it an edge; crossing one means two constraints
  // cross (refused: the caller resolves crossings first). Checked before any flip, so none removes it. (Not
  // before the owner check: a cavity may have rewritten another constraint's slots this round.)
  if (((cflags[t1] >> k1) & 1u) != 0u) {
    if (atomicCompSwap(ctl[CDT_CTL_ERROR], 0u, CDT_ERR_NOT_AN_EDGE) == 0u) ctl[CDT_CTL_ERROR_CONS] = e.cons;
    return;
  }
  uint side = e.info & CDT_SIDE_MASK;
  bool removes = (e.info & CDT_FIRST) != 0u || side == CDT_SIDE_END || (table[g - 1u].info & CDT_SIDE_MASK) == side;
  dvec2 P = pts[verts(3u * t1 + k1)], V1 = pts[verts(3u * t1 + cdt_next(k1))];
  dvec2 V2 = pts[verts(3u * t1 + cdt_prev(k1))], S = pts[verts(3u * t2 + k2)];
  // New triangles (p, v1, s) and (s, v2, p): strictly counter-clockwise iff the quadrilateral is strictly convex.
  bool convex = true;
  for (uint j = 0u; j < 2u && convex; ++j) convex = pred_orient2d(j == 0u ? P : S, j == 0u ? V1 : V2, j == 0u ? S : P) > 0;
  if (!convex) return;
  uint64_t key = cdt_claim_key(p.round, removes ? 0u : 1u, g);
  // One flip per constraint: only the constraint's smallest key may flip; it wins both of its slots, since only
  // candidates of the owner claim them.
  if (p.one_per_constraint != 0u) atomicMin(first_row[e.cons], key);
  atomicMin(claim[t1], key);
  atomicMin(claim[t2], key);
  table[g].flag = removes ? 1u : 2u;
}
