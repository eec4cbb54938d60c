// Body of the flip kernel (shaders/dt_flip.comp, and dt_flip_tail.comp with DT_TAIL defined).
//
// Flip pass, step 2: every request that won both claims flips its edge inside the same two slots,
//   t = (c@k, a@k+1, b@k+2), u = (d@j, b@j+1, a@j+2)  ->  t = (c, a, d), u = (d, b, c),
// and repairs the adjacency at once. t's edge k+2 and u's edge j+2 stay; t's edge k+1 (b->c) moves to u, index
// j, and u's edge j+1 (a->d) to t, index k; the new diagonal is t's k+1 and u's j+1. Whether a neighbour flips
// in this pass too, and where its edge goes, follows from the claims alone (final since step 1, read-only
// here) and partner[] (dt_moved): so each flip writes the final codes of its own four outer edges, and the back
// pointers of the neighbours that do not flip (each such edge has one flipping side: one writer). Both new
// triangles go to the next list (all edges but the diagonal to check); a losing request keeps its slot there
// (all edges) unless a winner flips that slot, and so lists it. The last workgroup sizes the next pass, empties
// this list and the exact lists for their next use, and counts the next pass if it has work.
//
// DT_TAIL: then, in the last workgroup, while the next list holds at most DT_TAIL_MAX entries, up to
// DT_TAIL_PASSES further passes (check with the exact stage inline, then flip) separated by workgroup barriers
// instead of dispatches: the long tail of nearly empty passes at the end of a round (2M uniform points: 180 of
// 230 passes had fewer than 1000 entries, each pass two launches and barriers). The buffers are coherent so
// that this workgroup sees the other workgroups' writes and its own across barriers.
#include "layout_dt.h"
#include "common.glsl"

#ifdef DT_TAIL
#define DT_COHERENT coherent
#define DT_EXACT 1
#define DT_CHECK
uint dt_epoch_now;  // the claim epoch of the pass being run (the tail's passes follow p.epoch)
#define DT_EPOCH dt_epoch_now
#else
#define DT_COHERENT
#endif

layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) DT_COHERENT buffer Verts { uint verts[]; };
layout(std430, binding = 1) DT_COHERENT buffer Nbrs { uint nbrs[]; };
layout(std430, binding = 2) DT_COHERENT buffer Claim { uint64_t claim[]; };
layout(std430, binding = 3) DT_COHERENT buffer Partner { uint partner[]; };
layout(std430, binding = 4) DT_COHERENT buffer List0 { uint list0[]; };
layout(std430, binding = 5) DT_COHERENT buffer List1 { uint list1[]; };
layout(std430, binding = 6) buffer Counters { uint counters[]; };
layout(std430, binding = 7) writeonly buffer Args { uint args[]; };
layout(std430, binding = 8) readonly buffer Points { dvec2 xy[]; };
layout(push_constant) uniform Push { DtFlipPush p; };

#define DT_CLAIMS
#define DT_APPEND
#define DT_LAST_GROUP
#include "dt_common.glsl"

uint list_get(uint s, uint i) { return s == 0u ? list0[i] : list1[i]; }
void list_set(uint s, uint i, uint v) {
  if (s == 0u)
    list0[i] = v;
  else
    list1[i] = v;
}

// The request that holds slot n's claim in this pass, if it won: its priority NBR(t, k), else DT_NONE.
uint winner_of(uint n) {
  uint64_t c = claim[n];
  if (!dt_claim_current(c)) return DT_NONE;
  uint r = uint(c), t = NBR_TRI(r);
  // A request claims its slot t and the neighbour u: n is one of them, whose claim is known to hold.
  if (n != t) return claim[t] == c ? r : DT_NONE;
  return claim[NBR_TRI(partner[t])] == c ? r : DT_NONE;
}

// Where edge l of slot n is after this pass; `flips`: n flips in this pass.
uint dt_moved(uint n, uint l, out bool flips) {
  uint r = winner_of(n);
  flips = r != DT_NONE;
  if (!flips) return NBR(n, l);
  uint t = NBR_TRI(r), k = NBR_EDGE(r), pc = partner[t];
  if (n == t) return l == dt_next(k) ? pc : NBR(n, l);
  return l == dt_next(NBR_EDGE(pc)) ? r : NBR(n, l);
}

// Slot q's outer edge e, whose old neighbour code was c: its final code, and the back pointer if that
// neighbour does not flip.
void link(uint q, uint e, uint c) {
  bool flips;
  uint f = dt_moved(NBR_TRI(c), NBR_EDGE(c), flips);
  nbrs[3u * q + e] = f;
  if (!flips) nbrs[3u * NBR_TRI(c) + NBR_EDGE(c)] = NBR(q, e);
}

// Entry i of list `src`: its work; returns how many entries (0, 1, 2) it adds to the next list, in out_a and
// out_b.
uint flip(uint src, uint i, out uint out_a, out uint out_b) {
  out_a = out_b = DT_NONE;
  uint entry = list_get(src, i);
  if (entry == DT_NONE || DT_ENTRY_MODE(entry) != DT_REQUEST) return 0u;
  uint t = DT_ENTRY_SLOT(entry), k = DT_ENTRY_EDGE(entry);
  uint w = winner_of(t);
  if (w != NBR(t, k)) {  // lost: keep t unless a winner flips it
    out_a = DT_ENTRY(t, DT_CHECK_ALL, 0u);
    return w == DT_NONE ? 1u : 0u;
  }
  uint uc = partner[t];
  uint u = NBR_TRI(uc), j = NBR_EDGE(uc);
  uint k1 = dt_next(k), k2 = dt_prev(k), j1 = dt_next(j), j2 = dt_prev(j);
  uint c = verts[3u * t + k], d = verts[3u * u + j];
  uint tn1 = nbrs[3u * t + k1], tn2 = nbrs[3u * t + k2], un1 = nbrs[3u * u + j1], un2 = nbrs[3u * u + j2];
  verts[3u * t + k2] = d;
  verts[3u * u + j2] = c;
  nbrs[3u * t + k1] = NBR(u, j1);
  nbrs[3u * u + j1] = NBR(t, k1);
  link(t, k, un1);
  link(t, k2, tn2);
  link(u, j, tn1);
  link(u, j2, un2);
  out_a = DT_ENTRY(t, DT_CHECK_SKIP, k1);
  out_b = DT_ENTRY(u, DT_CHECK_SKIP, j1);
  return 2u;
}

// Appends an invocation's 0..2 entries to list dst (every invocation of the workgroup calls it) and counts its
// flips.
void append(uint dst, uint count, uint a, uint b) {
  uint at = dt_append_base(DT_COUNT_LIST0 + dst, count);
  if (count > 0u) {
    if (at + count > p.capacity) {
      atomicAdd(counters[DT_OVERFLOW], 1u);
    } else {
      list_set(dst, at, a);
      if (count == 2u) list_set(dst, at + 1u, b);
    }
  }
  dt_count_add(DT_FLIPS, count == 2u ? 1u : 0u);
}

#ifdef DT_TAIL
shared uint tail_n;

// Entry i of list src: check its slot and request the flip, as dt_flip_check_inline.
void request(uint src, uint i) {
  list_set(src, i, dt_request(list_get(src, i)));
  if (dt_used_exact) atomicAdd(counters[DT_EXACT_CHECKS], 1u);
}

// The last workgroup, after the pass: further passes while the list is short. The list it leaves goes back
// into list 1 - p.src, which the next dispatched pass reads, with that pass's dispatch size.
void tail() {
  uint lid = gl_LocalInvocationIndex, home = 1u - p.src, cur = home, n = 0u;
  for (uint pass = 1u; pass <= DT_TAIL_PASSES; ++pass) {
    if (lid == 0u) tail_n = dt_count(DT_COUNT_LIST0 + cur);
    memoryBarrierBuffer();
    barrier();
    n = tail_n;
    if (n == 0u || n > DT_TAIL_MAX) break;
    if (lid == 0u) atomicAdd(counters[DT_TAIL_DONE], 1u);  // a pass run here (DT_FLIP_PASSES counted its list)
    dt_epoch_now = p.epoch + pass;
    for (uint base = 0u; base < n; base += DT_WG)
      if (base + lid < n) request(cur, base + lid);
    memoryBarrierBuffer();
    barrier();
    for (uint base = 0u; base < n; base += DT_WG) {
      uint a, b, count = 0u;
      if (base + lid < n) count = flip(cur, base + lid, a, b);
      append(1u - cur, count, a, b);
    }
    memoryBarrierBuffer();
    barrier();
    if (lid == 0u) {
      atomicExchange(counters[DT_COUNT_LIST0 + cur], 0u);
      if (dt_count(DT_COUNT_LIST0 + 1u - cur) > 0u) atomicAdd(counters[DT_FLIP_PASSES], 1u);
    }
    cur = 1u - cur;
  }
  if (lid == 0u) tail_n = dt_count(DT_COUNT_LIST0 + cur);
  memoryBarrierBuffer();
  barrier();
  n = tail_n;
  if (cur != home) {  // an odd number of tail passes: move the list home
    for (uint base = 0u; base < n; base += DT_WG)
      if (base + lid < n) list_set(home, base + lid, list_get(cur, base + lid));
    memoryBarrierBuffer();
    barrier();
    if (lid == 0u) {
      atomicExchange(counters[DT_COUNT_LIST0 + home], n);
      atomicExchange(counters[DT_COUNT_LIST0 + cur], 0u);
    }
  }
  if (lid == 0u) {
    dt_write_list_args(home, n);
    dt_write_list_args(1u - home, 0u);
  }
}
#endif

void main() {
#ifdef DT_TAIL
  dt_epoch_now = p.epoch;
#endif
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint a, b, count = 0u;
  if (i < counters[DT_COUNT_LIST0 + p.src]) count = flip(p.src, i, a, b);
  append(1u - p.src, count, a, b);
  if (dt_last_group()) {
    if (gl_LocalInvocationIndex == 0u) {
      uint dst = 1u - p.src, n = dt_count(DT_COUNT_LIST0 + dst);
      dt_write_list_args(dst, n);
      dt_write_list_args(p.src, 0u);
      counters[DT_COUNT_LIST0 + p.src] = 0u;
      counters[DT_EXACT_RELOC] = 0u;
      counters[DT_EXACT_FLIP] = 0u;
      if (n > 0u) counters[DT_FLIP_PASSES] += 1u;
    }
#ifdef DT_TAIL
    memoryBarrierBuffer();
    barrier();
    tail();
#endif
  }
}
