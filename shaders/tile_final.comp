// One invocation per slot: final[t] = 1 when slot t is a finite triangle whose closed circumdisk certainly lies in
// the tile's open rectangle (core/tiles.cpp, disk_inside: the same filter in doubles with the same error bounds);
// 0 otherwise, including every case the host would hand to interval arithmetic: a stricter test only makes the
// merge larger. Every operation `precise`, divisions correctly rounded (division.glsl) and no square root (the
// radius compared squared), so every device flags the same slots.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "division.glsl"
#include "tri_refs.glsl"

layout(local_size_x = TILE_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 pts[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) writeonly buffer Final { uint final_flag[]; };
layout(push_constant) uniform Push { TileFinalPush p; };

const double U = 1.1102230246251565e-16lf;  // 2^-53

// Whether the side at `offset` from a (gap: from the centre) is clear of the disk by more than every error:
// gap - radius > slack, as (gap - slack)^2 > r2 (1 + 16u) with gap - slack > 0.
bool clear(double offset, double gap, double e, double radius_err, double centre, double r2) {
  precise double slack = e + radius_err + 4.0lf * 2.0lf * U * (abs(offset) + centre);
  precise double g = gap - slack;
  precise double g2 = g * g;
  precise double bound = r2 * (1.0lf + 16.0lf * U);
  return g > 0.0lf && g2 > bound;
}

bool disk_inside(dvec2 a, dvec2 b, dvec2 c) {
  precise double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  double m = max(max(abs(bx), abs(by)), max(abs(cx), abs(cy)));
  precise double d = 2.0lf * (bx * cy - by * cx);
  precise double d_err = 4.0lf * 16.0lf * U * m * m;
  if (!(abs(d) > 64.0lf * d_err)) return false;
  precise double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  precise double nx = cy * b2 - by * c2, ny = bx * c2 - cx * b2;
  double ux = div_rn(nx, d), uy = div_rn(ny, d);
  double centre = max(abs(ux), abs(uy));
  precise double num = 36.0lf * U * m * m * m + centre * 16.0lf * U * m * m;
  precise double e = 4.0lf * (div_rn(num, abs(d)) + U * centre);
  precise double r2 = ux * ux + uy * uy;
  // The host's 3u |radius| with |ux| + |uy| >= radius in its place.
  precise double radius_err = 4.0lf * (1.5lf * e + 3.0lf * U * (abs(ux) + abs(uy)));
  precise double ox0 = a.x - p.x0, ox1 = p.x1 - a.x, oy0 = a.y - p.y0, oy1 = p.y1 - a.y;
  precise double gx0 = ox0 + ux, gx1 = ox1 - ux, gy0 = oy0 + uy, gy1 = oy1 - uy;
  if ((p.sides & TILE_SIDE_X0) != 0u && !clear(ox0, gx0, e, radius_err, centre, r2)) return false;
  if ((p.sides & TILE_SIDE_X1) != 0u && !clear(ox1, gx1, e, radius_err, centre, r2)) return false;
  if ((p.sides & TILE_SIDE_Y0) != 0u && !clear(oy0, gy0, e, radius_err, centre, r2)) return false;
  if ((p.sides & TILE_SIDE_Y1) != 0u && !clear(oy1, gy1, e, radius_err, centre, r2)) return false;
  return true;
}

void main() {
  uint t = linear_group_id() * TILE_WG + gl_LocalInvocationIndex;
  if (t >= p.num_slots) return;
  uint v0 = verts(3u * t), v1 = verts(3u * t + 1u), v2 = verts(3u * t + 2u);
  bool finite = v0 != INF_VERTEX && v1 != INF_VERTEX && v2 != INF_VERTEX;
  final_flag[t] = finite && disk_inside(pts[v0], pts[v1], pts[v2]) ? 1u : 0u;
}
