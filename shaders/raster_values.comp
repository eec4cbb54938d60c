// One invocation per cell of the band: the value of the triangle that owns it (raster_claim), by core/raster's
// formula, every operation `precise` and the divisions correctly rounded (division.glsl), so the double is
// the CPU's bit for bit; NODATA where no triangle holds the centre.
#version 450
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "common.glsl"
#include "division.glsl"
#include "raster_common.glsl"

layout(local_size_x = RASTER_WG) in;
layout(std430, binding = 3) readonly buffer Owner { uint owner[]; };
layout(std430, binding = 4) writeonly buffer Z { double z[]; };
layout(push_constant) uniform Push { RasterPush p; };

double interpolate(dvec3 a, dvec3 b, dvec3 c, double x, double y) {
  if (x == a.x && y == a.y) return a.z;
  if (x == b.x && y == b.y) return b.z;
  if (x == c.x && y == c.y) return c.z;
  precise double d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  precise double sn = (x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x);
  precise double tn = (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
  precise double s = div_rn(sn, d);
  precise double t = div_rn(tn, d);
  precise double v = a.z + s * (b.z - a.z) + t * (c.z - a.z);
  return v;
}

void main() {
  uint i = linear_group_id() * RASTER_WG + gl_LocalInvocationIndex;
  if (i >= p.rows * p.ncols) return;
  uint t = owner[i];
  if (t == RASTER_NO_TRI) {
    z[i] = params[RASTER_NODATA];
    return;
  }
  uint row = p.row0 + i / p.ncols, col = i % p.ncols;
  z[i] = interpolate(vertex(tris[3u * t]), vertex(tris[3u * t + 1u]), vertex(tris[3u * t + 2u]), centre_x(col),
                     centre_y(row));
}
