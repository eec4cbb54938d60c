// Shared by the radix-sort passes: tile of the current subgroup and the digit of key i for this pass.
#ifndef CDTGPU_RADIX_COMMON_GLSL
#define CDTGPU_RADIX_COMMON_GLSL

// Keys are uint words; a 64-bit key i is words 2i (low) and 2i+1 (high).
uint radix_digit(uint i) {
  uint word = p.wide != 0u ? keys_in[2u * i + (p.shift >> 5)] : keys_in[i];
  return (word >> (p.shift & 31u)) & (RADIX_BINS - 1u);
}

// Each subgroup owns one tile; tiles are numbered across workgroups.
uint radix_tile() { return linear_group_id() * gl_NumSubgroups + gl_SubgroupID; }

#endif
