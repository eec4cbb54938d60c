// Body of the flip kernel (shaders/dt_flip.comp, and dt_flip_tail.comp with DT_TAIL defined).
//
// Flip pass, step 2: every request that won both claims flips its edge inside the same two slots,
//   t = (c@k, a@k+1, b@k+2), u = (d@j, b@j+1, a@j+2)  ->  t = (c, a, d), u = (d, b, c),
// and repairs the adjacency at once. t's edge k+2 and u's edge j+2 stay; t's edge k+1 (b->c) moves to u, index
// j, and u's edge j+1 (a->d) to t, index k; the new diagonal is t's k+1 and u's j+1. Whether a neighbour flips
// in this pass too, and where its edge goes, follows from the claims alone (final since step 1, read-only
// here) and partner[] (dt_moved): so each flip writes the final codes of its own four outer edges, and the back
// pointers of the neighbours that do not flip (each such edge has one flipping side: one writer). Both new
// triangles go to the next list with their outer edges to check (not the diagonal; an edge whose other side
// flipped too is checked by the smaller slot of the two only); a losing request keeps its slot there (all
// edges) unless a winner flips that slot. The last workgroup sizes the next pass, empties
// this list and the exact lists for their next use, and counts the next pass if it has work.
//
// DT_TAIL: then, in the last workgroup, while the next list holds at most DT_TAIL_MAX entries, up to
// DT_TAIL_PASSES further passes (check with the exact stage inline, then flip) separated by workgroup barriers
// instead of dispatches: the long tail of nearly empty passes at the end of a round (2M uniform points: 180 of
// 230 passes had fewer than 1000 entries, each pass two launches and barriers). The buffers are coherent so
// that this workgroup sees the other workgroups' writes and its own across barriers; its lists and counts are
// in shared memory, so a pass waits on the loads of its checks and flips alone (H100, 2M uniform points:
// 10.0 -> 9.6 ms with the flip's loads issued before its writes).
#include "layout_dt.h"
#include "common.glsl"

#ifdef DT_TAIL
#define DT_COHERENT coherent
#define DT_TRI_WORDS TriWordsC
#define DT_EXACT 1
#define DT_CHECK
uint dt_epoch_now;  // the claim epoch of the pass being run (the tail's passes follow p.epoch)
#define DT_EPOCH dt_epoch_now
#else
#define DT_COHERENT
#define DT_TRI_WORDS TriWords
#endif

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) restrict readonly buffer VertsAt { DT_TRI_WORDS verts_at; };
#define verts(i) TRI_WORD(DT_TRI_WORDS, verts_at, i)
layout(std430, binding = 1) restrict readonly buffer NbrsAt { DT_TRI_WORDS nbrs_at; };
#define nbrs(i) TRI_WORD(DT_TRI_WORDS, nbrs_at, i)
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

#ifdef DT_TAIL
// The tail's flip lists, lists 2 and 3 below: a pass of at most DT_TAIL_MAX entries appends at most twice as
// many.
shared uint tail_list[2][2u * DT_TAIL_MAX];
#endif

uint list_get(uint s, uint i) {
#ifdef DT_TAIL
  if (s >= 2u) return tail_list[s - 2u][i];
#endif
  return s == 0u ? list0[i] : list1[i];
}
void list_set(uint s, uint i, uint v) {
#ifdef DT_TAIL
  if (s >= 2u) {
    tail_list[s - 2u][i] = v;
    return;
  }
#endif
  if (s == 0u)
    list0[i] = v;
  else
    list1[i] = v;
}

// The request that holds slot n's claim in this pass, if it won: its priority NBR(t, k), else DT_NONE; pc: the
// request's neighbour code NBR(u, j). Two dependent loads: partner[n] comes with the claim, should n hold
// its own request (short tail passes wait on these chains).
uint winner_of(uint n, out uint pc) {
  uint64_t c = claim[n];
  uint pn = partner[n];
  pc = 0u;
  if (!dt_claim_current(c)) return DT_NONE;
  uint r = uint(c), t = NBR_TRI(r);
  // A request claims its slot t and the neighbour u: n is one of them, whose claim is known to hold.
  pc = n == t ? pn : partner[t];
  return claim[n == t ? NBR_TRI(pn) : t] == c ? r : DT_NONE;
}

// Where edge l of slot n is after this pass; `flips`: n flips in this pass.
uint dt_moved(uint n, uint l, out bool flips) {
  uint pc, r = winner_of(n, pc);
  flips = r != DT_NONE;
  if (!flips) return NBR(n, l);
  uint t = NBR_TRI(r), k = NBR_EDGE(r);
  if (n == t) return l == dt_next(k) ? pc : NBR(n, l);
  return l == dt_next(NBR_EDGE(pc)) ? r : NBR(n, l);
}

// Slot q's outer edge e, whose old neighbour code was c and whose final code is f (dt_moved): the code, and
// the back pointer if that neighbour does not flip. Returns whether q's side checks the edge next pass: a
// neighbour that flips too lists it from its side as well, and the smaller slot of the two checks it.
bool link(uint q, uint e, uint c, uint f, bool flips) {
  nbrs(3u * q + e) = f;
  if (!flips) nbrs(3u * NBR_TRI(c) + NBR_EDGE(c)) = NBR(q, e);
  return !flips || q < NBR_TRI(f);
}

// Entry i of list `src`: its work; returns how many entries (0, 1, 2) it adds to the next list, in out_a and
// out_b; `flipped`: it flipped.
uint flip(uint src, uint i, out uint out_a, out uint out_b, out bool flipped) {
  out_a = out_b = DT_NONE;
  flipped = false;
  uint entry = list_get(src, i);
  if (entry == DT_NONE || DT_ENTRY_MODE(entry) != DT_REQUEST) return 0u;
  uint t = DT_ENTRY_SLOT(entry), k = DT_ENTRY_EDGE(entry), k1 = dt_next(k), k2 = dt_prev(k);
  uint c = verts(3u * t + k), tn1 = nbrs(3u * t + k1), tn2 = nbrs(3u * t + k2);  // read with the claim
  uint uc, w = winner_of(t, uc);
  if (w != NBR(t, k)) {  // lost: keep t unless a winner flips it
    out_a = DT_ENTRY(t, DT_CHECK_ALL, 0u);
    return w == DT_NONE ? 1u : 0u;
  }
  uint u = NBR_TRI(uc), j = NBR_EDGE(uc), j1 = dt_next(j), j2 = dt_prev(j);
  uint d = verts(3u * u + j), un1 = nbrs(3u * u + j1), un2 = nbrs(3u * u + j2);
  // Every read before the first write, so that the four neighbours' claim chains load side by side: a write
  // to nbrs could alias a later read of claim or partner as far as the compiler knows.
  bool f0, f1, f2, f3;
  uint m0 = dt_moved(NBR_TRI(un1), NBR_EDGE(un1), f0), m1 = dt_moved(NBR_TRI(tn2), NBR_EDGE(tn2), f1);
  uint m2 = dt_moved(NBR_TRI(tn1), NBR_EDGE(tn1), f2), m3 = dt_moved(NBR_TRI(un2), NBR_EDGE(un2), f3);
  verts(3u * t + k2) = d;
  verts(3u * u + j2) = c;
  nbrs(3u * t + k1) = NBR(u, j1);
  nbrs(3u * u + j1) = NBR(t, k1);
  bool ck = link(t, k, un1, m0, f0), ck2 = link(t, k2, tn2, m1, f1);
  bool cj = link(u, j, tn1, m2, f2), cj2 = link(u, j2, un2, m3, f3);
  flipped = true;
  uint ea = dt_entry_after(t, k1, ck2, ck), eb = dt_entry_after(u, j1, cj2, cj);
  out_a = ea == DT_NONE ? eb : ea;
  out_b = ea == DT_NONE ? DT_NONE : eb;
  return (ea == DT_NONE ? 0u : 1u) + (eb == DT_NONE ? 0u : 1u);
}

// Appends an invocation's 0..2 entries to list dst (every invocation of the workgroup calls it) and counts its
// flips.
void append(uint dst, uint count, uint a, uint b, bool flipped) {
  uint at = dt_append_base(DT_COUNT_LIST0 + dst, count);
  if (count > 0u) {
    if (at + count > p.capacity) {
      atomicAdd(counters[DT_OVERFLOW], 1u);
    } else {
      list_set(dst, at, a);
      if (count == 2u) list_set(dst, at + 1u, b);
    }
  }
  dt_count_add(DT_FLIPS, flipped ? 1u : 0u);
}

#ifdef DT_TAIL
// The tail's own counts and lists, in shared memory (it is the only workgroup running): its passes then wait
// on no global atomics or list loads. The list it leaves goes back to the global list when it stops.
shared uint tail_count[2];  // entries in tail_list 0 and 1
shared uint tail_flips, tail_passes, tail_listed;

// Entry i of list src: check its slot and request the flip, as dt_flip_check_inline.
void request(uint src, uint i) {
  list_set(src, i, dt_request(list_get(src, i)));
  if (dt_used_exact) atomicAdd(counters[DT_EXACT_CHECKS], 1u);
}

// append() for the tail: a shared atomic per invocation with entries.
void tail_append(uint dst, uint count, uint a, uint b, bool flipped) {
  if (flipped) atomicAdd(tail_flips, 1u);
  if (count == 0u) return;
  uint at = atomicAdd(tail_count[dst], count);
  if (at + count > 2u * DT_TAIL_MAX) {
    atomicAdd(counters[DT_OVERFLOW], 1u);
    return;
  }
  tail_list[dst][at] = a;
  if (count == 2u) tail_list[dst][at + 1u] = b;
}

// The last workgroup, after the pass: further passes while the list is short. The list it leaves goes back
// into list 1 - p.src, which the next dispatched pass reads, with that pass's dispatch size.
void tail() {
  uint lid = gl_LocalInvocationIndex, home = 1u - p.src, cur = 0u;
  if (lid == 0u) {
    tail_count[0] = dt_count(DT_COUNT_LIST0 + home);
    tail_count[1] = 0u;
    tail_flips = tail_passes = tail_listed = 0u;
  }
  barrier();
  uint n = tail_count[0];
  if (n == 0u || n > DT_TAIL_MAX) return;  // the pass's own counts and arguments stand
  for (uint base = 0u; base < n; base += DT_WG)
    if (base + lid < n) tail_list[0][base + lid] = list_get(home, base + lid);
  barrier();
  for (uint pass = 1u; pass <= DT_TAIL_PASSES; ++pass) {
    n = tail_count[cur];
    if (n == 0u || n > DT_TAIL_MAX) break;
    dt_epoch_now = p.epoch + pass;
    for (uint base = 0u; base < n; base += DT_WG)
      if (base + lid < n) request(2u + cur, base + lid);
    memoryBarrierBuffer();
    barrier();
    for (uint base = 0u; base < n; base += DT_WG) {
      uint a, b, count = 0u;
      bool flipped = false;
      if (base + lid < n) count = flip(2u + cur, base + lid, a, b, flipped);
      tail_append(1u - cur, count, a, b, flipped);
    }
    memoryBarrierBuffer();
    barrier();
    if (lid == 0u) {
      tail_count[cur] = 0u;
      tail_passes += 1u;                                    // a pass run here
      tail_listed += tail_count[1u - cur] > 0u ? 1u : 0u;  // DT_FLIP_PASSES counts non-empty lists
    }
    barrier();
    cur = 1u - cur;
  }
  n = tail_count[cur];
  for (uint base = 0u; base < n; base += DT_WG)
    if (base + lid < n) list_set(home, base + lid, tail_list[cur][base + lid]);
  if (lid == 0u) {
    atomicExchange(counters[DT_COUNT_LIST0 + home], n);
    atomicAdd(counters[DT_FLIPS], tail_flips);
    atomicAdd(counters[DT_TAIL_DONE], tail_passes);
    atomicAdd(counters[DT_FLIP_PASSES], tail_listed);
    dt_write_list_args(home, n);
  }
}
#endif

void main() {
#ifdef DT_TAIL
  dt_epoch_now = p.epoch;
#endif
  uint i = linear_group_id() * DT_WG + gl_LocalInvocationIndex;
  uint a, b, count = 0u;
  bool flipped = false;
  if (i < counters[DT_COUNT_LIST0 + p.src]) count = flip(p.src, i, a, b, flipped);
  append(1u - p.src, count, a, b, flipped);
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
