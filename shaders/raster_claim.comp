// One invocation per (triangle, row) work item: every centre of the row inside the triangle's closed area
// gets the triangle's index by atomicMin, so each cell ends with the smallest such index, whatever the order
// the invocations ran in: the CPU's first triangle in mesh order. Only the orientation filters run here;
// centres they cannot decide (on or next to an edge) go to a queue for raster_exact. With the exact stage in
// this shader the pass ran 35 times slower on lavapipe, though the stage itself is rarely reached.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "predicates.glsl"
#include "raster_common.glsl"

layout(local_size_x = RASTER_WG) in;
layout(std430, binding = 3) readonly buffer Spans { uvec4 spans[]; };
layout(std430, binding = 4) readonly buffer Offsets { uint offsets[]; };  // exclusive scan of the counts
layout(std430, binding = 5) buffer Owner { uint owner[]; };                // band cells, row-major
layout(std430, binding = 6) writeonly buffer Queue { uvec4 queue[]; };     // (triangle, row, column, 0)
layout(std430, binding = 7) buffer QueueCount { uint queue_count[]; };
layout(push_constant) uniform Push { RasterPush p; };

void main() {
  uint i = linear_group_id() * RASTER_WG + gl_LocalInvocationIndex;
  if (i >= p.items) return;
  // The last triangle whose first item is at or before i: its count is not zero, so i is one of its items.
  uint lo = 0u, hi = p.num_tris - 1u;
  while (lo < hi) {
    uint mid = (lo + hi + 1u) >> 1;
    if (offsets[mid] <= i) lo = mid; else hi = mid - 1u;
  }
  uint t = lo;
  uvec4 s = spans[t];
  uint row = s.x + (i - offsets[t]);
  int o = s.w == 1u ? 1 : -1;
  dvec2 v[3] = dvec2[3](vertex(tris[3u * t]).xy, vertex(tris[3u * t + 1u]).xy, vertex(tris[3u * t + 2u]).xy);
  double y = centre_y(row);
  uint base = (row - p.row0) * p.ncols;
  for (uint col = s.y; col <= s.z; ++col) {
    dvec2 q = dvec2(centre_x(col), y);
    bool inside = true, undecided = false;
    for (int e = 0; e < 3 && inside; ++e) {
      int side = pred_orient2d_filter(v[e], v[(e + 1) % 3], q);
      undecided = undecided || side == PRED_UNDECIDED;
      inside = side == PRED_UNDECIDED || side * o >= 0;
    }
    if (!inside) continue;
    if (!undecided) {
      atomicMin(owner[base + col], t);
    } else {
      uint slot = atomicAdd(queue_count[0], 1u);
      if (slot < p.queue_cap) queue[slot] = uvec4(t, row, col, 0u);
    }
  }
}
