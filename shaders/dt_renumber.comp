// Delaunay start, after the Morton sort: the build numbers the points in list (Morton) order, so that points,
// and the slots split at them, that lie together are read together. Point i of the build is the point with
// canonical id perm[i]; its coordinates are copied to xy_build[i] (dt_number_back maps everything back at the
// end). loc is set per list position: the first triangle's corners are vertices, every other point is
// "somewhere in slot 0", and the corners in slots 0..3 (written by dt_init with canonical ids) are renamed.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) buffer List { uint list[]; };
layout(std430, binding = 2) writeonly buffer Loc { uint loc[]; };
layout(std430, binding = 3) writeonly buffer BuildPoints { dvec2 xy_build[]; };
layout(std430, binding = 4) writeonly buffer Perm { uint perm[]; };
layout(std430, binding = 5) restrict readonly buffer VertsAt { TriWords verts_at; };
#define verts(i) TRI_WORD(TriWords, verts_at, i)
layout(push_constant) uniform Push { DtInitPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  uint pt = list[i];
  xy_build[i] = xy[pt];
  perm[i] = pt;
  list[i] = i;
  loc[i] = pt == p.a || pt == p.b || pt == p.c ? DT_INSERTED | NBR(0u, DT_INSIDE) : NBR(0u, DT_INSIDE);
  // The corners' places in dt_init's slots 0..3; one invocation writes each, none reads another's.
  if (pt == p.a) verts(0) = verts(6) = verts(10) = i;
  if (pt == p.b) verts(1) = verts(4) = verts(9) = i;
  if (pt == p.c) verts(2) = verts(3) = verts(7) = i;
}
