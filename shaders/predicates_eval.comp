// Evaluates the three predicates of shaders/predicates.glsl on quadruples of points, for
// tests/gpu_predicates_test.cpp: out[3i] = orient2d(p0, p1, p2), out[3i+1] = incircle(p0, p1, p2, p3),
// out[3i+2] = incircle_perturbed(p0, p1, p2, p3). The case count is the bound range of `quads` / 4.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "predicates.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Quads { dvec2 quads[]; };
layout(std430, binding = 1) writeonly buffer Signs { int signs[]; };

void main() {
  uint i = linear_group_id() * 64u + gl_LocalInvocationIndex;
  uint n = uint(quads.length()) / 4u;
  if (i >= n) return;
  dvec2 p0 = quads[4u * i], p1 = quads[4u * i + 1u], p2 = quads[4u * i + 2u], p3 = quads[4u * i + 3u];
  signs[3u * i] = pred_orient2d(p0, p1, p2);
  signs[3u * i + 1u] = pred_incircle(p0, p1, p2, p3);
  signs[3u * i + 2u] = pred_incircle_perturbed(p0, p1, p2, p3);
}
