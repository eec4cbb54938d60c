// Insertion round, step 3b, over the words of the granted list-position bits: numbers the splits in one
// dispatch. Each workgroup counts the set bits of DT_WG words and scans them: ranks[w] = granted positions
// before word w within its tile, ranks[n + 1 + tile] = the tile's total. The last workgroup turns the tile
// totals into their exclusive prefix and writes the number of splits to ranks[n] (dt_rank adds the two
// prefixes). A count pass and a multi-level scan did this in four dispatches, and every dependent dispatch
// costs ~4 us on the H100 (cdtgpu_microbench --chain), every round. The same dispatch clears the other copy of
// both bit sets (the build alternates two per round, so the next round needs no fills): p.capacity words of
// slot bits, p.max_steps words of position bits.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer GrantedAt { uint granted_at[]; };
layout(std430, binding = 1) coherent buffer Ranks { uint ranks[]; };  // tile totals: read by the last group
layout(std430, binding = 2) buffer Counters { uint counters[]; };
layout(std430, binding = 3) writeonly buffer NextGranted { uint next_granted[]; };
layout(std430, binding = 4) writeonly buffer NextGrantedAt { uint next_granted_at[]; };
layout(push_constant) uniform Push { DtRoundPush p; };  // n: words of granted_at in use

#define DT_LAST_GROUP
#define DT_NO_ARGS
#include "dt_common.glsl"

shared uint partial[DT_WG + 1];  // per subgroup: its inclusive total, then its exclusive prefix; [DT_WG]: all

// Exclusive prefix sum of v over the workgroup in the order of `rank` (subgroup by subgroup); total: the sum.
// Uniform control flow.
uint workgroup_exclusive(uint v, out uint total) {
  uint incl = subgroupInclusiveAdd(v);
  if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) partial[gl_SubgroupID] = incl;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint sum = 0u;
    for (uint s = 0u; s < gl_NumSubgroups; ++s) {
      uint x = partial[s];
      partial[s] = sum;
      sum += x;
    }
    partial[DT_WG] = sum;
  }
  barrier();
  uint r = partial[gl_SubgroupID] + incl - v;
  total = partial[DT_WG];
  barrier();  // partial is reused by the next call
  return r;
}

void main() {
  uint tile = linear_group_id(), tiles = (p.n + DT_WG - 1u) / DT_WG;
  uint rank = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
  uint w = tile * DT_WG + rank;
  if (w < p.capacity) next_granted[w] = 0u;
  if (w < p.max_steps) next_granted_at[w] = 0u;
  if (tile < tiles) {  // whole workgroups: the dispatch may be wider for the clearing
    uint total, before = workgroup_exclusive(w < p.n ? bitCount(granted_at[w]) : 0u, total);
    if (w < p.n) ranks[w] = before;
    if (rank == 0u) ranks[p.n + 1u + tile] = total;
  }
  if (dt_last_group()) {
    uint carry = 0u;
    for (uint b0 = 0u; b0 < tiles; b0 += DT_WG) {
      uint b = b0 + rank, total;
      uint before = workgroup_exclusive(b < tiles ? ranks[p.n + 1u + b] : 0u, total);
      if (b < tiles) ranks[p.n + 1u + b] = carry + before;
      carry += total;
    }
    if (rank == 0u) ranks[p.n] = carry;
  }
}
