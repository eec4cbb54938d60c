// Delaunay end: the slots' corners go back from build numbers (Morton order, dt_renumber) to canonical ids,
// and the coordinates to their canonical places. One invocation per corner in use and per point. Each corner
// also names its slot as one holding its vertex (vertex_slots: any of them, whichever store lands last; the
// constraint walks start there and their result does not depend on which).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer BuildPoints { dvec2 xy_build[]; };
layout(std430, binding = 1) readonly buffer Perm { uint perm[]; };
layout(std430, binding = 2) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(std430, binding = 3) writeonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 4) writeonly buffer VertexSlots { uint vertex_slots[]; };
layout(push_constant) uniform Push { DtRoundPush p; };  // n: points, base: slots in use

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i < 3u * p.base) {
    uint v = verts(i);
    if (v != INF_VERTEX) {
      verts(i) = perm[v];
      vertex_slots[perm[v]] = i / 3u;
    }
  }
  if (i < p.n) xy[perm[i]] = xy_build[i];
}
