// Exclusive scan of one block of SCAN_BLOCK uint32 per workgroup; optionally writes each block's total to
// block_sums for the next level. Subgroup scans, then the subgroup totals scanned by the first subgroup in
// gl_SubgroupSize steps, so any subgroup size gives the same result. `in` and `out` may be the same buffer.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "layout.h"
#include "common.glsl"

layout(local_size_x = SCAN_WG) in;
layout(std430, binding = 0) readonly buffer In { uint data_in[]; };
layout(std430, binding = 1) writeonly buffer Out { uint data_out[]; };
layout(std430, binding = 2) writeonly buffer Sums { uint block_sums[]; };
layout(push_constant) uniform Push { ScanPush p; };

shared uint tile[SCAN_BLOCK];
shared uint sg_prefix[SCAN_WG];
shared uint wg_total;

void main() {
  uint block = linear_group_id();
  uint base = block * SCAN_BLOCK;
  if (base >= p.n) return;  // whole workgroup: extra groups of a split dispatch
  uint li = gl_LocalInvocationIndex;
  for (uint k = 0; k < SCAN_ITEMS; ++k) {
    uint g = base + k * SCAN_WG + li;
    uint v = g < p.n ? data_in[g] : 0u;
    tile[k * SCAN_WG + li] = p.binarize != 0u ? uint(v != 0u) : v;
  }
  barrier();

  // Each invocation owns SCAN_ITEMS consecutive elements, ordered by its position in its subgroup.
  uint rank = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
  uint vals[SCAN_ITEMS];
  uint sum = 0;
  for (uint k = 0; k < SCAN_ITEMS; ++k) {
    vals[k] = tile[rank * SCAN_ITEMS + k];
    sum += vals[k];
  }
  uint incl = subgroupInclusiveAdd(sum);
  if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) sg_prefix[gl_SubgroupID] = incl;
  barrier();
  if (gl_SubgroupID == 0u) {
    uint carry = 0;
    for (uint b = 0; b < gl_NumSubgroups; b += gl_SubgroupSize) {
      uint j = b + gl_SubgroupInvocationID;
      uint v = j < gl_NumSubgroups ? sg_prefix[j] : 0u;
      uint x = subgroupExclusiveAdd(v);
      if (j < gl_NumSubgroups) sg_prefix[j] = carry + x;
      carry += subgroupAdd(v);
    }
    if (gl_SubgroupInvocationID == 0u) wg_total = carry;
  }
  barrier();
  uint prefix = sg_prefix[gl_SubgroupID] + incl - sum;
  for (uint k = 0; k < SCAN_ITEMS; ++k) {
    tile[rank * SCAN_ITEMS + k] = prefix;
    prefix += vals[k];
  }
  barrier();
  for (uint k = 0; k < SCAN_ITEMS; ++k) {
    uint g = base + k * SCAN_WG + li;
    if (g < p.n) data_out[g] = tile[k * SCAN_WG + li];
  }
  if (li == 0u && p.write_sums != 0u) block_sums[block] = wg_total;
}
