// The canonical form of a slot's triangle (core/canonical.hpp): rotated to start at its smallest vertex, counter-
// clockwise kept. Needs a readonly buffer `verts`. False for an infinite slot.
#ifndef CDTGPU_CANONICAL_COMMON_GLSL
#define CDTGPU_CANONICAL_COMMON_GLSL

bool canonical_triangle(uint t, out uvec3 tri) {
  uint v0 = verts(3u * t), v1 = verts(3u * t + 1u), v2 = verts(3u * t + 2u);
  tri = uvec3(v0, v1, v2);
  if (v0 == INF_VERTEX || v1 == INF_VERTEX || v2 == INF_VERTEX) return false;
  if (v1 < v0 && v1 < v2)
    tri = uvec3(v1, v2, v0);
  else if (v2 < v0 && v2 < v1)
    tri = uvec3(v2, v0, v1);
  return true;
}

#endif
