// Legalisation's first queue: the slots flipped during insertion and those of cavities after round 1 (every other
// edge still has both of its constrained Delaunay triangles: round 1's cavities were cut into the Delaunay
// triangulation itself, and a cavity's retriangulation of a CDT is the CDT with its segment; cavity slots carry
// no flip partner), or every finite slot when the input is not known to be Delaunay. Queue order depends on
// scheduling; nothing downstream depends on it (claims are keyed by edge, not by queue position).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout_cdt.h"
#include "common.glsl"
#include "subgroup_append.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 1) readonly buffer Stamp { uint stamp[]; };
layout(std430, binding = 2) writeonly buffer QStamp { uint qstamp[]; };
layout(std430, binding = 3) writeonly buffer Queue { uint queue[]; };
layout(std430, binding = 4) buffer Ctl { uint ctl[]; };
layout(std430, binding = 5) readonly buffer Partner { uint partner[]; };
layout(push_constant) uniform Push { CdtSlotsPush p; };

void main() {
  uint t = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (t >= p.n) return;
  if (p.all == 0u && (stamp[t] == CDT_NEVER || (stamp[t] == 1u && partner[t] == CDT_NEVER))) return;
  if (verts(3u * t) == INF_VERTEX || verts(3u * t + 1u) == INF_VERTEX || verts(3u * t + 2u) == INF_VERTEX) return;
  qstamp[t] = p.round;
  uint at;
  SUBGROUP_APPEND(at, ctl[CDT_CTL_NEXT]);
  queue[at] = t;
}
