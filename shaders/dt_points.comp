// Delaunay start, step 1: over all points, the y range (for Morton keys; x is sorted, so its range is the first
// and last point) and the point farthest from the line v0-v1 by a floating-point estimate of orient2d, ties to
// the smallest index. The host checks the candidate exactly. Every result is an atomicMin of a 64-bit key,
// reduced over the workgroup first, and skipped when the key is not below the word's value: every workgroup
// hits the same three words, where atomics queue (one per subgroup and word cost 0.13 ms at 2M points on the H100).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "layout_dt.h"
#include "common.glsl"
#include "dt_common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
// [0] min y, [1] ~max y (orderable 64-bit keys), [2] (~|orient| float key) << 32 | point; all start at ~0.
layout(std430, binding = 1) buffer Reduce { uint64_t red[]; };
layout(push_constant) uniform Push { DtPointsPush p; };

uint64_t orderable64(double d) {
  uvec2 w = unpackDouble2x32(d);
  uint64_t u = (uint64_t(w.y) << 32) | uint64_t(w.x);
  return (w.y & 0x80000000u) != 0u ? ~u : (u | (uint64_t(1) << 63));
}

// The subgroup minimum of a 64-bit value, from 32-bit subgroup operations: high word, then low word among the
// lanes that hold the minimal high word.
uint64_t subgroup_min64(uint64_t v) {
  uint hi = uint(v >> 32), lo = uint(v);
  uint hmin = subgroupMin(hi);
  uint lmin = subgroupMin(hi == hmin ? lo : 0xFFFFFFFFu);
  return (uint64_t(hmin) << 32) | uint64_t(lmin);
}

shared uint64_t part[3u * DT_WG];  // per subgroup: its three minima

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint64_t none = ~uint64_t(0);
  uint64_t k0 = none, k1 = none, k2 = none;
  if (i < p.n) {
    dvec2 q = xy[i];
    k0 = orderable64(q.y);
    k1 = ~k0;
    dvec2 a = xy[p.v0], b = xy[p.v1];
    double est = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    k2 = (uint64_t(~dt_orderable(float(abs(est)))) << 32) | uint64_t(i);
  }
  k0 = subgroup_min64(k0);
  k1 = subgroup_min64(k1);
  k2 = subgroup_min64(k2);
  if (subgroupElect()) {
    part[3u * gl_SubgroupID] = k0;
    part[3u * gl_SubgroupID + 1u] = k1;
    part[3u * gl_SubgroupID + 2u] = k2;
  }
  barrier();
  if (gl_LocalInvocationIndex < 3u) {
    uint w = gl_LocalInvocationIndex;
    uint64_t k = none;
    for (uint s = 0u; s < gl_NumSubgroups; ++s) k = min(k, part[3u * s + w]);
    // A plain read first: the minimum only falls, so a stale value can only cause an extra atomic.
    if (k < red[w]) atomicMin(red[w], k);
  }
}
