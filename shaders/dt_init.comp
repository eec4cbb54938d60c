// Delaunay start, step 2: the first triangle (a, b, c) (counter-clockwise) in slot 0 and the infinite triangle
// across each of its edges in slots 1..3; every point gets a 32-bit Morton key of its position in the bounding
// box, with its id as sort payload (dt_loc_init then places the points in slot 0).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "layout_dt.h"
#include "common.glsl"
#include "dt_common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) readonly buffer Reduce { uint64_t red[]; };
layout(std430, binding = 2) restrict readonly buffer VertsAt { TriWordsW verts_at; };
#define verts(i) TRI_WORD(TriWordsW, verts_at, i)
layout(std430, binding = 3) restrict readonly buffer NbrsAt { TriWordsW nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsW, nbrs_at, i)
layout(std430, binding = 4) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 5) writeonly buffer Ids { uint ids[]; };
layout(push_constant) uniform Push { DtInitPush p; };

double from_orderable64(uint64_t k) {
  uint64_t u = (k & (uint64_t(1) << 63)) != 0ul ? (k & ~(uint64_t(1) << 63)) : ~k;
  return packDouble2x32(uvec2(uint(u), uint(u >> 32)));
}

uint spread16(uint v) {
  v &= 0xFFFFu;
  v = (v | (v << 8)) & 0x00FF00FFu;
  v = (v | (v << 4)) & 0x0F0F0F0Fu;
  v = (v | (v << 2)) & 0x33333333u;
  v = (v | (v << 1)) & 0x55555555u;
  return v;
}

uint quantize(double v, double lo, double hi) {
  double f = hi > lo ? (v - lo) / (hi - lo) : 0.0lf;
  return uint(clamp(f, 0.0lf, 1.0lf) * 65535.0lf);
}

void main() {
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  if (i >= p.n) return;
  if (i == 0u) {
    // Finite (a, b, c); across edge 0 (b->c) slot 1 = (c, b, INF), edge 1 (c->a) slot 2 = (a, c, INF),
    // edge 2 (a->b) slot 3 = (b, a, INF). The infinite slots meet along their edges to INF.
    uint v[12] = uint[12](p.a, p.b, p.c, p.c, p.b, INF_VERTEX, p.a, p.c, INF_VERTEX, p.b, p.a, INF_VERTEX);
    uint n[12] = uint[12](NBR(1u, 2u), NBR(2u, 2u), NBR(3u, 2u),    //
                          NBR(3u, 1u), NBR(2u, 0u), NBR(0u, 0u),    //
                          NBR(1u, 1u), NBR(3u, 0u), NBR(0u, 1u),    //
                          NBR(2u, 1u), NBR(1u, 0u), NBR(0u, 2u));
    for (uint k = 0u; k < 12u; ++k) {
      verts(k) = v[k];
      nbrs(k) = n[k];
    }
  }
  dvec2 q = xy[i];
  double y0 = from_orderable64(red[0]), y1 = from_orderable64(~red[1]);
  uint qx = quantize(q.x, xy[0].x, xy[p.n - 1u].x), qy = quantize(q.y, y0, y1);
  keys[i] = (spread16(qx) | (spread16(qy) << 1)) >> p.key_shift;
  ids[i] = i;
}
