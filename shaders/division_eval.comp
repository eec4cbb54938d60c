// Correctly rounded division (division.glsl) from a given starting quotient, for tests/gpu_raster_test.cpp:
// out[i] = div_rn_from(a, b, q0) for cases (a, b, q0); tests pass quotients a few ulps off to exercise the
// correction, which the device's own division may never need.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "division.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Cases { double cases[]; };
layout(std430, binding = 1) writeonly buffer Out { double quotients[]; };

void main() {
  uint i = linear_group_id() * 64u + gl_LocalInvocationIndex;
  uint n = uint(cases.length()) / 3u;
  if (i >= n) return;
  quotients[i] = div_rn_from(cases[3u * i], cases[3u * i + 1u], cases[3u * i + 2u]);
}
