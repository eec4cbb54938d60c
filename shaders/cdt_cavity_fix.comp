// Neighbour codes of the outer edges of this round's cavities (cdt_cavity.comp), one invocation per edge, as
// cdt_fix does for flips: the edge still holds the code of its old neighbour beyond. When that neighbour was
// rewritten this round (a flip or another cavity), remap says where its old edge went; otherwise the neighbour
// gets our new code. Each entry has exactly one writer.
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
layout(std430, binding = 3) readonly buffer Fixes { uint fixes[]; };
layout(std430, binding = 4) readonly buffer Ctl { uint ctl[]; };
layout(push_constant) uniform Push { CdtRoundPush p; };

void main() {
  uint i = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (i >= ctl[CDT_CTL_FIXES]) return;
  uint ours = fixes[i];
  uint t = NBR_TRI(ours), e = NBR_EDGE(ours);
  uint code = nbrs(3u * t + e);
  uint x = NBR_TRI(code), j = NBR_EDGE(code);
  if (stamp[x] == p.round)
    nbrs(3u * t + e) = remap[3u * x + j];
  else
    nbrs(3u * x + j) = ours;
}
