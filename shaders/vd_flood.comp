// Voronoi first stage, step 2 (flood): one jump-flooding pass (Rong & Tan 2006). Each cell takes, of its own
// site and those of the eight cells `step` away, the one whose point is nearest its centre (ties: the smaller
// build number, so every run floods alike). Passes with steps W/2 .. 1 and a last one of 1 (JFA+1) leave a
// digital Voronoi diagram with few errors; the errors cost repairs, never exactness (docs/gpu-delaunay.md).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) readonly buffer Src { uint src[]; };
layout(std430, binding = 2) writeonly buffer Dst { uint dst[]; };
layout(push_constant) uniform Push { VdGridPush p; };
#include "vd_common.glsl"

void main() {
  uint c = linear_group_id() * VD_WG + gl_LocalInvocationIndex;
  if (c >= p.width * p.height) return;
  uint cx = c % p.width, cy = c / p.width;
  dvec2 centre = vd_centre(cx, cy);
  uint best = src[c];
  double best_d = 0.0lf;
  if (best != VD_NONE) {
    dvec2 d = xy[best] - centre;
    best_d = dot(d, d);
  }
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      int x = int(cx) + dx * int(p.step), y = int(cy) + dy * int(p.step);
      if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= int(p.width) || y >= int(p.height)) continue;
      uint s = src[uint(y) * p.width + uint(x)];
      if (s == VD_NONE || s == best) continue;
      dvec2 d = xy[s] - centre;
      double e = dot(d, d);
      if (best == VD_NONE || e < best_d || (e == best_d && s < best)) {
        best = s;
        best_d = e;
      }
    }
  dst[c] = best;
}
