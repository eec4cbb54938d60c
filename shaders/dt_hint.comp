// Delaunay, the first round after the sampled ones (DelaunayBuilder::sample_stride): the points that did not
// walk yet start from the slot of the sample point listed before them (Morton order: a near point), or of the
// next one when that one is a vertex already (its slot then is the one it was inserted into: older). Reads
// sample positions only and writes the others: no order between invocations matters.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) buffer Loc { uint loc[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint s = p.stride, i0 = i - i % s;
  if (i >= p.n || i == i0 || (loc[i] & DT_INSERTED) != 0u) return;
  uint code = loc[i0];
  if ((code & DT_INSERTED) != 0u && i0 + s < p.n && (loc[i0 + s] & DT_INSERTED) == 0u) code = loc[i0 + s];
  loc[i] = NBR(NBR_TRI(code & ~DT_INSERTED), DT_INSIDE);
}
