// Stream compaction, last step: element i with a non-zero flag goes to out[offsets[i]] (offsets = exclusive
// scan of the 0/1 flags); the last invocation writes the number kept.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"

layout(local_size_x = COMPACT_WG) in;
layout(std430, binding = 0) readonly buffer Values { uint values[]; };
layout(std430, binding = 1) readonly buffer Flags { uint flags[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 3) writeonly buffer Out { uint out_values[]; };
layout(std430, binding = 4) writeonly buffer Count { uint count[]; };
layout(push_constant) uniform Push { CompactPush p; };

void main() {
  uint i = linear_group_id() * COMPACT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  bool keep = flags[i] != 0u;
  uint at = offsets[i];
  if (keep) out_values[at] = values[i];
  if (i == p.n - 1u) count[0] = at + uint(keep);
}
