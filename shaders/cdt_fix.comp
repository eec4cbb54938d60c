// Neighbour codes after a round of flips, one invocation per flip. A flipped slot's outer edges (0 and 2) still
// hold the neighbour codes from before the round. When that neighbour was flipped too, our code is replaced by
// where its old edge went (remap); otherwise the neighbour, untouched this round, gets our new code. Each
// neighbour entry has exactly one writer and flipped slots are read only by their own invocation: no races.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_cdt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) restrict readonly buffer NbrsAt { TriWords nbrs_at; };
#define nbrs(i) TRI_WORD(TriWords, nbrs_at, i)
layout(std430, binding = 1) readonly buffer Remap { uint remap[]; };
layout(std430, binding = 2) readonly buffer Stamp { uint stamp[]; };
layout(std430, binding = 3) readonly buffer Flips { uvec2 flips[]; };
layout(std430, binding = 4) readonly buffer Ctl { uint ctl[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

void main() {
  uint i = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (i >= ctl[CDT_CTL_FLIPS]) return;
  uvec2 f = flips[i];
  for (uint s = 0u; s < 2u; ++s) {
    uint t = s == 0u ? f.x : f.y;
    for (uint e = 0u; e < 3u; e += 2u) {
      uint code = nbrs(3u * t + e);
      uint x = NBR_TRI(code), j = NBR_EDGE(code);
      if (stamp[x] == p.round)
        nbrs(3u * t + e) = remap[3u * x + j];
      else
        nbrs(3u * x + j) = NBR(t, e);
    }
  }
}
