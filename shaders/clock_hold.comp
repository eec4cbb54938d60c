// One workgroup busy for a while (gpu/clock_hold): the device counts as working, so its clock stays up while the
// host prepares. Each invocation steps a chain of numbers and writes where it ended, so the loop is kept and a
// test can check that every step ran.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x = CLOCK_HOLD_WG) in;
layout(std430, binding = 0) writeonly buffer Sink { uint sink[]; };
layout(push_constant) uniform Push { ClockHoldPush p; };

// A multiply after a shift and xor: unlike a multiply-add, no compiler folds a run of these into one.
uint step(uint x) { return (x ^ (x >> 15)) * 2246822519u; }
#define STEP4 x = step(x); x = step(x); x = step(x); x = step(x);
#define STEP16 STEP4 STEP4 STEP4 STEP4

// 64 steps a turn, written out: lavapipe ends a loop after 65535 turns, nested or not (steps <= CLOCK_HOLD_MAX).
void main() {
  uint x = p.seed + gl_LocalInvocationIndex;
  for (uint r = 0u; r < p.steps / 64u; ++r) {
    STEP16 STEP16 STEP16 STEP16
  }
  for (uint i = 0u; i < p.steps % 64u; ++i) x = step(x);
  sink[gl_LocalInvocationIndex] = x;
}
