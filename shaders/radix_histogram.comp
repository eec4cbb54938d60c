// Radix sort pass, step 1: per-tile digit counts, stored digit-major (hist[digit * num_tiles + tile]) so one
// exclusive scan of hist gives every (digit, tile) its first output position, tiles in order: a stable sort.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#include "layout.h"
#include "common.glsl"

layout(local_size_x = RADIX_WG) in;
layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) writeonly buffer Hist { uint hist[]; };
layout(push_constant) uniform Push { RadixPush p; };

#include "radix_common.glsl"

shared uint counts[RADIX_MAX_SUBGROUPS * RADIX_BINS];

void main() {
  if (linear_group_id() * gl_NumSubgroups >= p.num_tiles) return;  // whole workgroup past the end
  uint tile = radix_tile();
  uint own = gl_SubgroupID * RADIX_BINS;
  for (uint d = gl_SubgroupInvocationID; d < RADIX_BINS; d += gl_SubgroupSize) counts[own + d] = 0u;
  barrier();
  if (tile < p.num_tiles) {
    uint start = tile * p.tile_size;
    uint end = min(start + p.tile_size, p.n);
    for (uint i = start + gl_SubgroupInvocationID; i < end; i += gl_SubgroupSize)
      atomicAdd(counts[own + radix_digit(i)], 1u);
  }
  barrier();
  if (tile < p.num_tiles)
    for (uint d = gl_SubgroupInvocationID; d < RADIX_BINS; d += gl_SubgroupSize)
      hist[d * p.num_tiles + tile] = counts[own + d];
}
