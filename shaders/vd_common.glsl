// Helpers of the Voronoi first stage (shaders/vd_*.comp): the grid of VdGridPush p.
#ifndef CDTGPU_VD_COMMON_GLSL
#define CDTGPU_VD_COMMON_GLSL

uint vd_axis(double v, double lo, uint cells) {
  double f = floor((v - lo) / p.cell);
  return uint(clamp(f, 0.0lf, double(cells - 1u)));
}

uint vd_cell(dvec2 q) { return vd_axis(q.y, p.y0, p.height) * p.width + vd_axis(q.x, p.x0, p.width); }

dvec2 vd_centre(uint cx, uint cy) {
  return dvec2(p.x0 + (double(cx) + 0.5lf) * p.cell, p.y0 + (double(cy) + 0.5lf) * p.cell);
}

#endif
