// Voronoi first stage, step 3 (dual): every grid corner where three or four regions meet gives the dual
// triangles of its sites, taken counter-clockwise around the corner (cells (x, y), (x+1, y), (x+1, y+1),
// (x, y+1)); four sites give two triangles sharing the first one. Appended in any order (the host sorts
// them), one atomic per workgroup: ~2 triangles per site on one counter would queue (shaders/subgroup_append.glsl
// has the H100's cost). Nothing here is trusted, the host checks the result exactly (gpu/voronoi_check.cpp).
// A triangle the orientation filter finds clockwise or flat blames its corners here already (each once, by a
// flag per point, into a list): the host's first check would blame them too, so with any blamed the host
// demotes them without downloading or checking the dual. Triangles the filter cannot decide go to the host,
// and only then does the host check orientations again (the filter's decisions are exact: `precise`, error
// bound as in core/predicates).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "layout_vd.h"
#include "common.glsl"

layout(local_size_x = VD_WG) in;
layout(std430, binding = 0) readonly buffer Grid { uint grid[]; };
layout(std430, binding = 1) writeonly buffer Tris { uint tris[]; };
layout(std430, binding = 2) buffer Count { uint count[]; };
layout(std430, binding = 3) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 4) buffer Blamed { uint blamed[]; };           // per point: 1 once listed
layout(std430, binding = 5) writeonly buffer BlameList { uint blame_list[]; };  // at most one entry per point
layout(push_constant) uniform Push { VdGridPush p; };
#include "predicates.glsl"

void blame(uint v) {
  if (atomicExchange(blamed[v], 1u) == 0u) blame_list[atomicAdd(count[VD_COUNT_BLAMED], 1u)] = v;
}

// Blames the corners of (a, b, c) when it is surely not counter-clockwise; counts it when the filter cannot
// tell (the host then checks every triangle's orientation exactly, else none).
void check(uint a, uint b, uint c) {
  int o = pred_orient2d_filter(xy[a], xy[b], xy[c]);
  if (o == PRED_UNDECIDED) atomicAdd(count[VD_COUNT_UNDECIDED], 1u);
  else if (o <= 0) {
    blame(a);
    blame(b);
    blame(c);
  }
}

shared uint sg_part[VD_WG];  // per subgroup: its total, then the workgroup's sum before it
shared uint wg_base;

void main() {
  uint v = linear_group_id() * VD_WG + gl_LocalInvocationIndex;
  uint w = p.width - 1u;
  uint d[4];
  uint t = 0u;
  if (p.width >= 2u && p.height >= 2u && v < w * (p.height - 1u)) {
    uint x = v % w, y = v / w;
    uint c = y * p.width + x;
    uint s[4] = uint[4](grid[c], grid[c + 1u], grid[c + 1u + p.width], grid[c + p.width]);
    // The distinct sites in cyclic order: drop each that repeats its predecessor (around the cycle).
    uint m = 0u;
    for (uint k = 0u; k < 4u; ++k)
      if (s[k] != s[(k + 3u) % 4u] && s[k] != VD_NONE) d[m++] = s[k];
    // Two regions touching twice give no triangle.
    if (m >= 3u && !(m == 4u && (d[0] == d[2] || d[1] == d[3]))) t = m - 2u;
  }
  // Uniform control flow from here: the workgroup reserves its triangles with one atomic.
  uint before = subgroupExclusiveAdd(t), total = subgroupAdd(t);
  if (subgroupElect()) sg_part[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint sum = 0u;
    for (uint k = 0u; k < gl_NumSubgroups; ++k) {
      uint x = sg_part[k];
      sg_part[k] = sum;
      sum += x;
    }
    wg_base = sum > 0u ? atomicAdd(count[VD_COUNT_TRIS], sum) : 0u;
  }
  barrier();
  if (t == 0u) return;
  uint at = wg_base + sg_part[gl_SubgroupID] + before;
  if (at + t > p.n) {
    atomicAdd(count[VD_COUNT_OVERFLOW], 1u);
    return;
  }
  check(d[0], d[1], d[2]);
  if (t == 2u) check(d[0], d[2], d[3]);
  tris[3u * at] = d[0];
  tris[3u * at + 1u] = d[1];
  tris[3u * at + 2u] = d[2];
  if (t == 2u) {
    tris[3u * at + 3u] = d[0];
    tris[3u * at + 4u] = d[2];
    tris[3u * at + 5u] = d[3];
  }
}
