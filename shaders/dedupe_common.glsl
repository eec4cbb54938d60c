// Doubles as order-preserving 64-bit keys (uvec2: low word, high word), for sorting points by (x, y).
#ifndef CDTGPU_DEDUPE_COMMON_GLSL
#define CDTGPU_DEDUPE_COMMON_GLSL

// IEEE bits -> unsigned key with the same order: negatives get every bit flipped, the rest the sign bit set.
// -0.0 becomes +0.0 first, since the two are equal points.
uvec2 order_key(uvec2 bits) {
  if (bits.y == 0x80000000u && bits.x == 0u) bits.y = 0u;
  if ((bits.y & 0x80000000u) != 0u) return ~bits;
  return uvec2(bits.x, bits.y | 0x80000000u);
}

#endif
