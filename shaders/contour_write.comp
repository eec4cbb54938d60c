// One invocation per triangle of the chunk: its segment at each level it crosses, at offsets[i] onwards (level
// order). The steps and formulas are core/contours.cpp's: above = z >= level, the falling and rising edges of
// the counter-clockwise walk, the point on an edge from its lower end (the upper end itself when it is at the
// level), t = (level - u.z) / (v.z - u.z) correctly rounded (division.glsl), every operation `precise`.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "division.glsl"
#include "contour_common.glsl"

layout(local_size_x = CONTOUR_WG) in;
layout(std430, binding = 3) readonly buffer First { uint first[]; };
layout(std430, binding = 4) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 5) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 6) writeonly buffer Segments { SegmentRecord segs[]; };
layout(push_constant) uniform Push { ContourPush p; };

// u below the level, v at or above it.
dvec2 crossing(dvec3 u, dvec3 v, double level) {
  if (v.z == level) return v.xy;
  precise double t = div_rn(level - u.z, v.z - u.z);
  precise double x = u.x + t * (v.x - u.x);
  precise double y = u.y + t * (v.y - u.y);
  return dvec2(x, y);
}

void main() {
  uint i = linear_group_id() * CONTOUR_WG + gl_LocalInvocationIndex;
  if (i >= p.num_tris) return;
  uint n = counts[i];
  if (n == 0u) return;
  uint t = p.tri0 + i;
  dvec3 v[3] = dvec3[3](vertex(tris[3u * t]), vertex(tris[3u * t + 1u]), vertex(tris[3u * t + 2u]));
  // A clockwise triangle (never in a canonical mesh) walks the other way round: the CPU's float test.
  precise double turn = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
  bool clockwise = turn < 0.0lf;
  for (uint j = 0u; j < n; ++j) {
    uint k = first[i] + j;
    double level = levels[k];
    bool above[3] = bool[3](v[0].z >= level, v[1].z >= level, v[2].z >= level);
    int falling = -1, rising = -1;
    for (int e = 0; e < 3; ++e) {
      int f = (e + 1) % 3;
      if (above[e] && !above[f]) falling = e;
      if (!above[e] && above[f]) rising = e;
    }
    int ff = (falling + 1) % 3, rf = (rising + 1) % 3;
    dvec2 pf = crossing(v[ff], v[falling], level);  // falling: above -> below, so the lower end is ff
    dvec2 pr = crossing(v[rising], v[rf], level);
    SegmentRecord s;
    s.tri = t;
    s.level = k;
    s.pad = 0u;
    if (clockwise) {
      s.edges = uint(rising) | (uint(falling) << 2);
      s.px = pr.x; s.py = pr.y; s.qx = pf.x; s.qy = pf.y;
    } else {
      s.edges = uint(falling) | (uint(rising) << 2);
      s.px = pf.x; s.py = pf.y; s.qx = pr.x; s.qy = pr.y;
    }
    segs[offsets[i] + j] = s;
  }
}
