// Cavity insertion, one invocation per constraint c that crosses 1..CDT_CAVITY_MAX edges and owns every
// triangle it crosses this round (T_0 .. T_K, the influence domain, so no other constraint touches them): the
// K + 1 triangles are replaced at once by the constrained Delaunay triangulations of the two pseudo-polygons
// left and right of a-b (Anglada's choice: the apex whose circle with the base holds no other chain vertex,
// CGAL's perturbation for ties), written into the same K + 1 slots. Inserting a segment this way into a CDT
// gives the CDT with the segment; owned domains are disjoint, so the cavities of one round commute. c is done
// (its edge marked), and its rows leave the table so the flip passes skip them; longer or contested
// constraints go on by flips. Outer edges keep their old neighbour codes and are listed for cdt_cavity_fix
// (remap says where each old outer edge went, as after a flip); every chain vertex's vmap entry names a new
// slot holding it (a later count walk whose start slot was rewritten here starts from it).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout_cdt.h"
#include "common.glsl"
#include "subgroup_append.glsl"
#include "predicates.glsl"
#include "cdt_common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 pts[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
layout(std430, binding = 3) readonly buffer Cons { uvec2 cons[]; };
layout(std430, binding = 4) buffer Start { uint start[]; };
layout(std430, binding = 5) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 7) buffer Table { CdtCross table[]; };
layout(std430, binding = 8) readonly buffer Owner { uint64_t owner[]; };
layout(std430, binding = 9) buffer CFlags { uint cflags[]; };
layout(std430, binding = 10) writeonly buffer Remap { uint remap[]; };
layout(std430, binding = 11) writeonly buffer Stamp { uint stamp[]; };
layout(std430, binding = 12) writeonly buffer Partner { uint partner[]; };
layout(std430, binding = 13) writeonly buffer VMap { uint vmap[]; };
layout(std430, binding = 14) writeonly buffer Fixes { uint fixes[]; };
layout(std430, binding = 15) buffer Ctl { uint ctl[]; };
layout(push_constant) uniform Push { CdtWalkPush p; };

#define CHAIN (CDT_CAVITY_MAX + 2u)  // vertices of one chain, a and b included

// Per chain (0 left of a->b, 1 right): vertices a .. b, and per chain edge j (vertices j, j + 1) the old outer
// edge as (slot, edge), its neighbour code beyond and its constrained bit, read before any slot is rewritten.
// In shared memory, a column per invocation (no barriers: nobody reads another's column): private arrays indexed
// at run time live in slow local memory.
shared uint sh_v[2u * CHAIN * CDT_WG], sh_at[2u * CHAIN * CDT_WG], sh_out[2u * CHAIN * CDT_WG];
shared uint sh_range[CHAIN * CDT_WG], sh_code[CHAIN * CDT_WG];  // the split stack: (i | j << 16), base code
#define CHAIN_V(side, j) sh_v[((side) * CHAIN + (j)) * CDT_WG + gl_LocalInvocationIndex]
#define CHAIN_AT(side, j) sh_at[((side) * CHAIN + (j)) * CDT_WG + gl_LocalInvocationIndex]
#define CHAIN_OUT(side, j) sh_out[((side) * CHAIN + (j)) * CDT_WG + gl_LocalInvocationIndex]
#define STACK_RANGE(k) sh_range[(k) * CDT_WG + gl_LocalInvocationIndex]
#define STACK_CODE(k) sh_code[(k) * CDT_WG + gl_LocalInvocationIndex]
uint chain_len[2];

void add_outer(uint side, uint t, uint e) {
  uint j = chain_len[side] - 2u;  // the edge ending at the chain's newest vertex
  CHAIN_AT(side, j) = NBR(t, e);
  CHAIN_OUT(side, j) = nbrs(3u * t + e) | (((cflags[t] >> e) & 1u) << 31);  // NBR codes use 30 bits
}

// The code of the same edge seen from the triangle beyond it.
uint beyond(uint code) { return nbrs(3u * NBR_TRI(code) + NBR_EDGE(code)); }

void add_vertex(uint side, uint v) { CHAIN_V(side, chain_len[side]++) = v; }

void main() {
  uint c = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (c >= p.m) return;
  uint k_rows = counts[c];
  if (k_rows == 0u || k_rows > CDT_CAVITY_MAX || start[c] == CDT_NEVER || ctl[CDT_CTL_TOTAL] > p.capacity) return;
  uint base = offsets[c];
  uint64_t okey = cdt_owner_key(p.round, c);

  // T_0 .. T_K: T_i holds row i's edge (i < K), T_K is beyond the last one; all must be c's.
  uint t_last = NBR_TRI(beyond(table[base + k_rows - 1u].edge));
  if (owner[t_last] != okey) return;
  for (uint i = 0u; i < k_rows; ++i)
    if (owner[NBR_TRI(table[base + i].edge)] != okey) return;
  for (uint i = 0u; i < k_rows; ++i) {  // a crossed constraint: refused, as in cdt_insert_claim
    uint e = table[base + i].edge;
    if (((cflags[NBR_TRI(e)] >> NBR_EDGE(e)) & 1u) != 0u) {
      if (atomicCompSwap(ctl[CDT_CTL_ERROR], 0u, CDT_ERR_NOT_AN_EDGE) == 0u) ctl[CDT_CTL_ERROR_CONS] = c;
      return;
    }
  }

  // The chains. T_0 = (a, R, L) from a's corner k; the segment leaves it across R-L.
  uint a = cons[c].x, b = cons[c].y;
  uint t = NBR_TRI(table[base].edge), k = NBR_EDGE(table[base].edge);
  uint right = verts(3u * t + cdt_next(k)), left = verts(3u * t + cdt_prev(k));
  chain_len[0] = 0u;
  chain_len[1] = 0u;
  add_vertex(0u, a);
  add_vertex(0u, left);
  add_outer(0u, t, cdt_next(k));  // a-L, opposite R
  add_vertex(1u, a);
  add_vertex(1u, right);
  add_outer(1u, t, cdt_prev(k));  // a-R, opposite L
  for (uint i = 0u; i < k_rows; ++i) {
    // T_{i+1} = (w, L, R) from its apex corner ku, entered across L-R.
    uint code = beyond(table[base + i].edge);
    uint u = NBR_TRI(code), ku = NBR_EDGE(code), w = verts(3u * u + ku);
    uint side = table[base + i].info & CDT_SIDE_MASK;
    if (side == CDT_SIDE_END) {
      add_vertex(0u, b);
      add_outer(0u, u, cdt_prev(ku));  // L-b, opposite R
      add_vertex(1u, b);
      add_outer(1u, u, cdt_next(ku));  // R-b, opposite L
    } else if (side == CDT_SIDE_LEFT) {
      add_vertex(0u, w);
      add_outer(0u, u, cdt_prev(ku));  // L-w, opposite R
    } else {
      add_vertex(1u, w);
      add_outer(1u, u, cdt_next(ku));  // R-w, opposite L
    }
  }

  // Each polygon split from its base down: left as a .. b (base a-b), right as b .. a (base b-a), so every new
  // triangle (chain[i], chain[j], apex) is counter-clockwise, its edge 2 the base, edge 1 apex-chain[i] and edge 0
  // chain[j]-apex. A stack of intervals (i, j) with the code of the edge across their base.
  uint fix_at = 0u;
  {  // this invocation's k_rows + 3 outer edges in the fix list, one atomic per subgroup
    uint n = k_rows + 3u, sum = subgroupAdd(n), first = 0u;
    if (subgroupElect()) first = atomicAdd(ctl[CDT_CTL_FIXES], sum);
    fix_at = subgroupBroadcastFirst(first) + subgroupExclusiveAdd(n);
  }
  uint made = 0u, outer = 0u, top = 0u;
  for (uint side = 0u; side < 2u; ++side) {
    uint n = chain_len[side];
    uint sp = 0u;
    STACK_RANGE(0u) = (n - 1u) << 16;
    STACK_CODE(0u) = CDT_NEVER;  // the base a-b: the other polygon's top triangle
    sp = 1u;
    while (sp > 0u) {
      --sp;
      uint i = STACK_RANGE(sp) & 0xFFFFu, j = STACK_RANGE(sp) >> 16, across = STACK_CODE(sp);
      // Chain position x of this polygon: the left chain as is, the right one reversed.
      uint vi = CHAIN_V(side, side == 0u ? i : n - 1u - i), vj = CHAIN_V(side, side == 0u ? j : n - 1u - j);
      uint apex = i + 1u;
      for (uint x = i + 2u; x < j; ++x) {
        uint va = CHAIN_V(side, side == 0u ? apex : n - 1u - apex), vx = CHAIN_V(side, side == 0u ? x : n - 1u - x);
        if (pred_incircle_perturbed(pts[vi], pts[vj], pts[va], pts[vx]) > 0) apex = x;
      }
      uint vapex = CHAIN_V(side, side == 0u ? apex : n - 1u - apex);
      uint s = made < k_rows ? NBR_TRI(table[base + made].edge) : t_last;  // the rows are not rewritten yet
      ++made;
      verts(3u * s) = vi;
      verts(3u * s + 1u) = vj;
      verts(3u * s + 2u) = vapex;
      stamp[s] = p.round;
      partner[s] = CDT_NEVER;
      vmap[vi] = s;
      vmap[vj] = s;
      vmap[vapex] = s;
      uint flags = 0u;
      if (across == CDT_NEVER) {
        if (side == 0u) {
          top = s;
        } else {  // the constraint a-b, between the two top triangles
          nbrs(3u * s + 2u) = NBR(top, 2u);
          nbrs(3u * top + 2u) = NBR(s, 2u);
        }
        flags = 4u;
      } else {
        nbrs(3u * s + 2u) = across;
        nbrs(3u * NBR_TRI(across) + NBR_EDGE(across)) = NBR(s, 2u);
      }
      // Edge 0 = chain[j]-apex (interval apex..j), edge 1 = apex-chain[i] (interval i..apex).
      for (uint e = 0u; e < 2u; ++e) {
        uint lo = e == 0u ? apex : i, hi = e == 0u ? j : apex;
        if (hi - lo >= 2u) {
          STACK_RANGE(sp) = lo | (hi << 16);
          STACK_CODE(sp) = NBR(s, e);
          ++sp;
          continue;
        }
        // A chain edge: chain position lo of this polygon is chain edge lo (left) or n - 2 - lo (right).
        uint ce = side == 0u ? lo : n - 2u - lo;
        uint old = CHAIN_OUT(side, ce);
        nbrs(3u * s + e) = old & 0x7FFFFFFFu;
        flags |= (old >> 31) << e;
        uint at = CHAIN_AT(side, ce);
        remap[3u * NBR_TRI(at) + NBR_EDGE(at)] = NBR(s, e);
        fixes[fix_at + outer++] = NBR(s, e);
      }
      cflags[s] = flags;
    }
  }

  start[c] = CDT_NEVER;
  for (uint i = 0u; i < k_rows; ++i) table[base + i].cons = CDT_NEVER;
  SUBGROUP_ADD(ctl[CDT_CTL_CAVITIES], 1u);
}
