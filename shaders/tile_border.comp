// One invocation per slot, after tile_final: a final slot lists each edge whose neighbour across is not final
// (another tile's, the merge's, or an infinite slot: the hull) as (from, to) counter-clockwise, so the final
// triangle is on its left; a slot that is not final gets INF_VERTEX as its first vertex, so the canonical sort
// (gpu/canonical) leaves it out. Slots read only their own vertices, so the writes race with nothing. count[0]
// counts every border edge, also those past `capacity` (the host then runs this pass again, larger).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "tri_refs.glsl"

layout(local_size_x = TILE_WG) in;
layout(std430, binding = 0) restrict buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 2) readonly buffer Final { uint final_flag[]; };
layout(std430, binding = 3) writeonly buffer Border { uvec2 border[]; };
layout(std430, binding = 4) buffer Count { uint count[]; };
layout(push_constant) uniform Push { TileFinalPush p; };

void main() {
  uint t = linear_group_id() * TILE_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots) return;
  if (final_flag[t] == 0u) {
    verts(3u * t) = INF_VERTEX;
    return;
  }
  for (uint k = 0u; k < 3u; ++k) {
    uint code = nbrs(3u * t + k);
    if (code != NO_TRI && final_flag[NBR_TRI(code)] != 0u) continue;
    // The edge opposite vertex k runs from vertex k + 1 to k + 2.
    uint i = atomicAdd(count[0], 1u);
    if (i < p.capacity) border[i] = uvec2(verts(3u * t + (k + 1u) % 3u), verts(3u * t + (k + 2u) % 3u));
  }
}
