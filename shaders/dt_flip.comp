// Flip pass, step 2: every request that won both claims flips its edge inside the same two slots,
//   t = (c@k, a@k+1, b@k+2), u = (d@j, b@j+1, a@j+2)  ->  t = (c, a, d), u = (d, b, c),
// and repairs the adjacency at once. t's edge k+2 and u's edge j+2 stay; t's edge k+1 (b->c) moves to u, index
// j, and u's edge j+1 (a->d) to t, index k; the new diagonal is t's k+1 and u's j+1. Whether a neighbour flips
// in this pass too, and where its edge goes, follows from the claims alone (final since step 1, read-only
// here) and partner[] (dt_moved): so each flip writes the final codes of its own four outer edges, and the back
// pointers of the neighbours that do not flip (each such edge has one flipping side: one writer). Both new
// triangles go to the next list (all edges but the diagonal to check); a losing request keeps its slot there
// (all edges) unless a winner flips that slot, and so lists it. The last workgroup sizes the next pass, empties
// this list and the exact lists for their next use, and counts the next pass if it has work.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) buffer Verts { uint verts[]; };
layout(std430, binding = 1) buffer Nbrs { uint nbrs[]; };
layout(std430, binding = 2) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 3) readonly buffer Partner { uint partner[]; };
layout(std430, binding = 4) readonly buffer List { uint list[]; };
layout(std430, binding = 5) writeonly buffer Next { uint next_list[]; };
layout(std430, binding = 6) buffer Counters { uint counters[]; };
layout(std430, binding = 7) writeonly buffer Args { uint args[]; };
layout(push_constant) uniform Push { DtFlipPush p; };

#define DT_CLAIMS
#define DT_APPEND
#define DT_LAST_GROUP
#include "dt_common.glsl"

// The request that holds slot n's claim in this pass, if it won: its priority NBR(t, k), else DT_NONE.
uint winner_of(uint n) {
  uint64_t c = claim[n];
  if (!dt_claim_current(c)) return DT_NONE;
  uint r = uint(c), t = NBR_TRI(r);
  return claim[t] == c && claim[NBR_TRI(partner[t])] == c ? r : DT_NONE;
}

// Where edge l of slot n is after this pass; `flips`: n flips in this pass.
uint dt_moved(uint n, uint l, out bool flips) {
  uint r = winner_of(n);
  flips = r != DT_NONE;
  if (!flips) return NBR(n, l);
  uint t = NBR_TRI(r), k = NBR_EDGE(r), pc = partner[t];
  if (n == t) return l == dt_next(k) ? pc : NBR(n, l);
  return l == dt_next(NBR_EDGE(pc)) ? r : NBR(n, l);
}

// Slot q's outer edge e, whose old neighbour code was c: its final code, and the back pointer if that
// neighbour does not flip.
void link(uint q, uint e, uint c) {
  bool flips;
  uint f = dt_moved(NBR_TRI(c), NBR_EDGE(c), flips);
  nbrs[3u * q + e] = f;
  if (!flips) nbrs[3u * NBR_TRI(c) + NBR_EDGE(c)] = NBR(q, e);
}

// Entry i's work; returns how many entries (0, 1, 2) it adds to the next list, in out_a and out_b.
uint flip(uint i, out uint out_a, out uint out_b) {
  out_a = out_b = DT_NONE;
  uint entry = list[i];
  if (entry == DT_NONE || DT_ENTRY_MODE(entry) != DT_REQUEST) return 0u;
  uint t = DT_ENTRY_SLOT(entry), k = DT_ENTRY_EDGE(entry);
  uint w = winner_of(t);
  if (w != NBR(t, k)) {  // lost: keep t unless a winner flips it
    out_a = DT_ENTRY(t, DT_CHECK_ALL, 0u);
    return w == DT_NONE ? 1u : 0u;
  }
  uint uc = partner[t];
  uint u = NBR_TRI(uc), j = NBR_EDGE(uc);
  uint k1 = dt_next(k), k2 = dt_prev(k), j1 = dt_next(j), j2 = dt_prev(j);
  uint c = verts[3u * t + k], d = verts[3u * u + j];
  uint tn1 = nbrs[3u * t + k1], tn2 = nbrs[3u * t + k2], un1 = nbrs[3u * u + j1], un2 = nbrs[3u * u + j2];
  verts[3u * t + k2] = d;
  verts[3u * u + j2] = c;
  nbrs[3u * t + k1] = NBR(u, j1);
  nbrs[3u * u + j1] = NBR(t, k1);
  link(t, k, un1);
  link(t, k2, tn2);
  link(u, j, tn1);
  link(u, j2, un2);
  out_a = DT_ENTRY(t, DT_CHECK_SKIP, k1);
  out_b = DT_ENTRY(u, DT_CHECK_SKIP, j1);
  return 2u;
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint a, b, count = 0u;
  if (i < counters[DT_COUNT_LIST0 + p.src]) count = flip(i, a, b);
  uint at = dt_append_base(DT_COUNT_LIST0 + 1u - p.src, count);
  if (count > 0u) {
    if (at + count > p.capacity) {
      atomicAdd(counters[DT_OVERFLOW], 1u);
    } else {
      next_list[at] = a;
      if (count == 2u) next_list[at + 1u] = b;
    }
  }
  uint flips = subgroupAdd(count == 2u ? 1u : 0u);
  if (subgroupElect() && flips > 0u) atomicAdd(counters[DT_FLIPS], flips);
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) {
    uint dst = 1u - p.src, n = dt_count(DT_COUNT_LIST0 + dst);
    dt_write_args(dst == 0u ? DT_ARGS_LIST0 : DT_ARGS_LIST1, n);
    counters[DT_COUNT_LIST0 + p.src] = 0u;
    counters[DT_EXACT_RELOC] = 0u;
    counters[DT_EXACT_FLIP] = 0u;
    if (n > 0u) counters[DT_FLIP_PASSES] += 1u;
  }
}
