// Helpers of the constraint passes (shaders/cdt_*.comp): claim keys, control-block indirect arguments, and the
// edge flip that every flipping pass shares. Needs GL_EXT_shader_explicit_arithmetic_types_int64.
//
// Claim words are 64-bit and never reset: the top 31 bits are (2^31 - 1 - round), so a claim of this round is
// smaller than any claim left from an earlier round and atomicMin ignores the old ones; bit 32 is a class (0
// wins over 1) and the low 32 bits a unique id, which orders the claimants of one round.
#ifndef CDTGPU_CDT_COMMON_GLSL
#define CDTGPU_CDT_COMMON_GLSL

// murmur3's 32-bit finaliser: a bijection, so distinct ids keep distinct keys.
uint cdt_mix(uint h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

uint64_t cdt_round_bits(uint round) { return uint64_t(0x7FFFFFFFu - round) << 33; }

// Owner of a triangle this round: the smallest constraint index whose domain holds it.
uint64_t cdt_owner_key(uint round, uint cons) { return cdt_round_bits(round) | uint64_t(cons); }

// Claim of a flip this round: class `late` (0 or 1; class 0 wins conflicts), then a hash of the flip's id (a
// table row or an edge code), fresh every round, so that of a run of adjacent candidates about one in three
// wins instead of only the first, and no schedule repeats. The smallest key in the round always wins both its
// triangles: every round with a candidate flips something.
uint64_t cdt_claim_key(uint round, uint late, uint id) {
  return cdt_round_bits(round) | (uint64_t(late) << 32) | uint64_t(cdt_mix(id ^ cdt_mix(round * 0x9e3779b9u)));
}

uint cdt_next(uint k) { return k == 2u ? 0u : k + 1u; }
uint cdt_prev(uint k) { return k == 0u ? 2u : k - 1u; }

#ifdef CDT_FLIP_BUFFERS
// Flips the edge opposite corner k1 of slot t1 (opposite k2 in slot t2), writing the two new triangles into
// the same two slots. Old t1 = (p, v1, v2), old t2 = (s, v2, v1); new t1 = (p, v1, s), new t2 = (s, v2, p),
// the new diagonal p-s is edge 1 of both. The four outer edges keep their old neighbour codes; remap records
// where each of them went, so that cdt_fix.comp can repair the codes on both sides without reading slots
// another flip is writing. Constrained-edge bits move with their edges. Caller owns both slots this round.
void cdt_flip(uint t1, uint k1, uint t2, uint k2, uint round) {
  uint a1 = cdt_next(k1), b1 = cdt_prev(k1), a2 = cdt_next(k2), b2 = cdt_prev(k2);
  uint p = verts(3u * t1 + k1), v1 = verts(3u * t1 + a1), v2 = verts(3u * t1 + b1), s = verts(3u * t2 + k2);
  uint nA = nbrs(3u * t1 + b1);  // edge p-v1
  uint nB = nbrs(3u * t1 + a1);  // edge v2-p
  uint nC = nbrs(3u * t2 + b2);  // edge s-v2
  uint nD = nbrs(3u * t2 + a2);  // edge v1-s
  uint f1 = cflags[t1], f2 = cflags[t2];
  uint fA = (f1 >> b1) & 1u, fB = (f1 >> a1) & 1u, fC = (f2 >> b2) & 1u, fD = (f2 >> a2) & 1u;
  verts(3u * t1) = p;
  verts(3u * t1 + 1u) = v1;
  verts(3u * t1 + 2u) = s;
  verts(3u * t2) = s;
  verts(3u * t2 + 1u) = v2;
  verts(3u * t2 + 2u) = p;
  nbrs(3u * t1) = nD;
  nbrs(3u * t1 + 1u) = NBR(t2, 1u);
  nbrs(3u * t1 + 2u) = nA;
  nbrs(3u * t2) = nB;
  nbrs(3u * t2 + 1u) = NBR(t1, 1u);
  nbrs(3u * t2 + 2u) = nC;
  cflags[t1] = fD | (fA << 2);
  cflags[t2] = fB | (fC << 2);
  remap[3u * t1 + b1] = NBR(t1, 2u);
  remap[3u * t1 + a1] = NBR(t2, 0u);
  remap[3u * t2 + b2] = NBR(t2, 2u);
  remap[3u * t2 + a2] = NBR(t1, 0u);
  stamp[t1] = round;
  stamp[t2] = round;
  partner[t1] = t2;
  partner[t2] = t1;
}
#endif

#endif
