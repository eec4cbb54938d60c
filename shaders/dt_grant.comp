// Insertion round, step 3, over the slots and one more: flags[t] = 1 when slot t's point won every claim it
// made (0 for t = n, so that the exclusive scan's last entry is the number of splits). The scan numbers the
// splits in slot order, two new slots each.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_dt.h"
#include "common.glsl"

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Pick { uint pickw[]; };
layout(std430, binding = 1) readonly buffer Claim { uint64_t claim[]; };
layout(std430, binding = 2) writeonly buffer Flags { uint flags[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_CLAIMS
#include "dt_common.glsl"

void main() {
  uint t = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (t > p.n) return;
  bool won = false;
  if (t < p.n && pickw[2u * t] != DT_NONE) {
    uint sc = pickw[2u * t + 1u];
    uint64_t key = dt_claim_key(t);
    won = claim[t] == key && (sc == DT_NONE || claim[NBR_TRI(sc)] == key);
  }
  flags[t] = won ? 1u : 0u;
}
