// One invocation per queued (triangle, row, column) of raster_claim: the centre is tested with exact
// orient2d and, inside the closed triangle, claimed by atomicMin like the others.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "predicates.glsl"
#include "raster_common.glsl"

layout(local_size_x = RASTER_WG) in;
layout(std430, binding = 3) readonly buffer Spans { uvec4 spans[]; };
layout(std430, binding = 4) readonly buffer Queue { uvec4 queue[]; };
layout(std430, binding = 5) readonly buffer QueueCount { uint queue_count[]; };
layout(std430, binding = 6) buffer Owner { uint owner[]; };
layout(push_constant) uniform Push { RasterPush p; };

void main() {
  uint i = linear_group_id() * RASTER_WG + gl_LocalInvocationIndex;
  if (i >= min(queue_count[0], p.queue_cap)) return;
  uvec4 w = queue[i];
  uint t = w.x;
  int o = spans[t].w == 1u ? 1 : -1;
  dvec2 v[3] = dvec2[3](vertex(tris[3u * t]).xy, vertex(tris[3u * t + 1u]).xy, vertex(tris[3u * t + 2u]).xy);
  dvec2 q = dvec2(centre_x(w.z), centre_y(w.y));
  bool inside = true;
  for (int e = 0; e < 3 && inside; ++e) inside = pred_orient2d(v[e], v[(e + 1) % 3], q) * o >= 0;
  if (inside) atomicMin(owner[(w.y - p.row0) * p.ncols + w.z], t);
}
