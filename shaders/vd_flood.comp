// Voronoi first stage, step 2 (flood): one jump-flooding pass (Rong & Tan 2006). Each cell takes, of its own
// site and those of the eight cells `step` away, the one whose point is nearest its centre (ties: the smaller
// build number, so every run floods alike). Passes with steps W/2 .. 1 and a last one of 1 (JFA+1) leave a
// digital Voronoi diagram with few errors; the errors cost repairs, never exactness (docs/gpu-delaunay.md).
// Distances are in float cell units from vd_seed's site positions: the flood only has to be deterministic,
// the exact checks and flips fix the rest. A workgroup floods a 16 x 16 tile (a subgroup a 16 x 2 strip or
// more), so neighbouring cells, which mostly share sites, fetch the same few positions. A repair's flood
// starts from the last grid with holes (vd_clear) and jumps 2^k .. 1, 1 only (gpu/voronoi_start.cpp); its last
// pass counts the cells left empty, and any sends the repair back to a full flood.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Sites { vec2 site[]; };
layout(std430, binding = 1) readonly buffer Src { uint src[]; };
layout(std430, binding = 2) writeonly buffer Dst { uint dst[]; };
layout(std430, binding = 3) buffer Count { uint count[]; };
layout(push_constant) uniform Push { VdGridPush p; };

void main() {
  uint g = linear_group_id(), tiles_x = (p.width + VD_TILE - 1u) / VD_TILE;
  uint cx = (g % tiles_x) * VD_TILE + gl_LocalInvocationIndex % VD_TILE;
  uint cy = (g / tiles_x) * VD_TILE + gl_LocalInvocationIndex / VD_TILE;
  if (cx >= p.width || cy >= p.height) return;
  uint c = cy * p.width + cx;
  vec2 centre = vec2(float(cx) + 0.5, float(cy) + 0.5);
  uint best = src[c];
  float best_d = 0.0;
  if (best != VD_NONE) {
    vec2 d = site[best] - centre;
    best_d = dot(d, d);
  }
  for (int dy = -1; dy <= 1; ++dy) {
    int y = int(cy) + dy * int(p.step);
    if (y < 0 || y >= int(p.height)) continue;
    for (int dx = -1; dx <= 1; ++dx) {
      int x = int(cx) + dx * int(p.step);
      if ((dx == 0 && dy == 0) || x < 0 || x >= int(p.width)) continue;
      uint s = src[uint(y) * p.width + uint(x)];
      if (s == VD_NONE || s == best) continue;
      vec2 d = site[s] - centre;
      float e = dot(d, d);
      if (best == VD_NONE || e < best_d || (e == best_d && s < best)) {
        best = s;
        best_d = e;
      }
    }
  }
  dst[c] = best;
  if (p.n != 0u && best == VD_NONE) atomicAdd(count[VD_COUNT_EMPTY], 1u);  // the last pass: none expected
}
