// Radix sort pass, step 2: each subgroup walks its tile in order, gl_SubgroupSize keys at a time. Lanes with
// the same digit find each other with 8 ballots (one per digit bit); a key's rank among them is the count of
// matching lower lanes, so equal digits keep their input order (stable) whatever the subgroup size.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout.h"
#include "common.glsl"

layout(local_size_x = RADIX_WG) in;
layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 3) writeonly buffer ValuesOut { uint values_out[]; };
layout(std430, binding = 4) readonly buffer Offsets { uint offsets[]; };  // scanned histogram
layout(push_constant) uniform Push { RadixPush p; };

#include "radix_common.glsl"

shared uint next[RADIX_MAX_SUBGROUPS * RADIX_BINS];  // per subgroup: next output position of each digit

void main() {
  if (linear_group_id() * gl_NumSubgroups >= p.num_tiles) return;
  uint tile = radix_tile();
  if (tile >= p.num_tiles) return;  // uniform per subgroup; no workgroup barrier below
  uint own = gl_SubgroupID * RADIX_BINS;
  for (uint d = gl_SubgroupInvocationID; d < RADIX_BINS; d += gl_SubgroupSize)
    next[own + d] = offsets[d * p.num_tiles + tile];
  subgroupMemoryBarrierShared();
  subgroupBarrier();

  uint start = tile * p.tile_size;
  uint end = min(start + p.tile_size, p.n);
  for (uint c = start; c < end; c += gl_SubgroupSize) {
    uint i = c + gl_SubgroupInvocationID;
    bool valid = i < end;
    uint d = valid ? radix_digit(i) : 0u;
    uvec4 match = subgroupBallot(valid);
    for (uint b = 0; b < 8u; ++b) {
      bool bit = ((d >> b) & 1u) != 0u;
      uvec4 set = subgroupBallot(bit);
      match &= bit ? set : ~set;
    }
    uint rank = subgroupBallotExclusiveBitCount(match);
    uint count = subgroupBallotBitCount(match);
    uint base = valid ? next[own + d] : 0u;
    subgroupMemoryBarrierShared();
    subgroupBarrier();
    if (valid) {
      uint dst = base + rank;
      if (p.wide != 0u) {
        keys_out[2u * dst] = keys_in[2u * i];
        keys_out[2u * dst + 1u] = keys_in[2u * i + 1u];
      } else {
        keys_out[dst] = keys_in[i];
      }
      values_out[dst] = values_in[i];
      if (rank + 1u == count) next[own + d] = base + count;
    }
    subgroupMemoryBarrierShared();
    subgroupBarrier();
  }
}
