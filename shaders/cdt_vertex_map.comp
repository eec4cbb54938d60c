// Vertex -> a slot that holds it: vmap[v] = the smallest slot with v as a corner (vmap filled with ~0 first).
// The walks start from it; the smallest slot keeps the result independent of scheduling.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_cdt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 1) buffer VMap { uint vmap[]; };
layout(push_constant) uniform Push { CdtSlotsPush p; };

void main() {
  uint t = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (t >= p.n) return;
  for (uint k = 0u; k < 3u; ++k) {
    uint v = verts(3u * t + k);
    if (v != INF_VERTEX) atomicMin(vmap[v], t);
  }
}
