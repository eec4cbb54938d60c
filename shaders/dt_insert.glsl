// The per-bid bodies of an insertion round's steps (claim, grant, split, fix), shared by the dispatched
// kernels (dt_claim, dt_grant, dt_split, dt_split_fix: one per step, over the bid list) and dt_insert_small
// (all four in one workgroup while the slots are few). The including shader declares the buffers a body names,
// defines the step macros it uses and, for split and fix, DT_SPLIT_NUMBER(t, at): the number of slot t's split
// (its winner at list position `at`) among the round's splits, which names its two new slots.
#ifndef CDTGPU_DT_INSERT_GLSL
#define CDTGPU_DT_INSERT_GLSL

#ifdef DT_INSERT_CLAIM
// The point that won slot t's bid claims what its split rewrites: t alone (inside: 1->3), or t and the
// neighbour s across the edge it lies on (2->4; s may be infinite). A claim is an atomicMin of dt_claim_key(t)
// on each slot: the smallest requester always wins all of its claims, so every round inserts something. The
// code NBR(s, edge in s) goes to the high word of pick[t] for the later steps (the low word is the winner's
// list position).
void dt_claim_bid(uint t) {
  uint k = NBR_EDGE(loc[pickw[2u * t]]);
  uint sc = k < 3u ? nbrs(3u * t + k) : DT_NONE;
  pickw[2u * t + 1u] = sc;
  atomicMin(claim[t], dt_claim_key(t));
  if (k < 3u) atomicMin(claim[NBR_TRI(sc)], dt_claim_key(t));
}
#endif

#ifdef DT_INSERT_GRANT
// Slot t's split is granted when its point won every claim it made.
bool dt_grant_bid(uint t) {
  uint sc = pickw[2u * t + 1u];
  uint64_t key = dt_claim_key(t);
  return claim[t] == key && (sc == DT_NONE || claim[NBR_TRI(sc)] == key);
}
#endif

#ifdef DT_INSERT_SPLIT
// Slot t's split, if granted (dt_split's comment has the new triangles).
void dt_split_bid(uint t) {
  if (!dt_granted(t)) return;
  uint at = pickw[2u * t], sc = pickw[2u * t + 1u], pt = list[at];
  uint k = NBR_EDGE(loc[at]);
  uint X = p.base + 2u * DT_SPLIT_NUMBER(t, at), Y = X + 1u;
  if (k == DT_INSIDE) {
    uint v0 = verts(3u * t), v1 = verts(3u * t + 1u), v2 = verts(3u * t + 2u);
    uint n1 = nbrs(3u * t + 1u), n2 = nbrs(3u * t + 2u);
    verts(3u * t) = pt;
    nbrs(3u * t + 1u) = NBR(X, 0u);
    nbrs(3u * t + 2u) = NBR(Y, 0u);
    verts(3u * X) = v0;
    verts(3u * X + 1u) = pt;
    verts(3u * X + 2u) = v2;
    nbrs(3u * X) = NBR(t, 1u);
    nbrs(3u * X + 1u) = n1;
    nbrs(3u * X + 2u) = NBR(Y, 1u);
    verts(3u * Y) = v0;
    verts(3u * Y + 1u) = v1;
    verts(3u * Y + 2u) = pt;
    nbrs(3u * Y) = NBR(t, 2u);
    nbrs(3u * Y + 1u) = NBR(X, 2u);
    nbrs(3u * Y + 2u) = n2;
    info[t] = NBR(X, DT_INSIDE);
    return;
  }
  uint s = NBR_TRI(sc), j = NBR_EDGE(sc);
  uint i1 = dt_next(k), i2 = dt_prev(k), j1 = dt_next(j), j2 = dt_prev(j);
  uint c = verts(3u * t + k), a = verts(3u * t + i1), b = verts(3u * t + i2), d = verts(3u * s + j);
  uint tn1 = nbrs(3u * t + i1), sn1 = nbrs(3u * s + j1);
  // t = (c, a, p)
  verts(3u * t + i2) = pt;
  nbrs(3u * t + k) = NBR(Y, j);
  nbrs(3u * t + i1) = NBR(X, i2);
  // X = (c, p, b)
  verts(3u * X + k) = c;
  verts(3u * X + i1) = pt;
  verts(3u * X + i2) = b;
  nbrs(3u * X + k) = NBR(s, j);
  nbrs(3u * X + i1) = tn1;
  nbrs(3u * X + i2) = NBR(t, i1);
  // s = (d, b, p)
  verts(3u * s + j2) = pt;
  nbrs(3u * s + j) = NBR(X, k);
  nbrs(3u * s + j1) = NBR(Y, j2);
  // Y = (d, p, a)
  verts(3u * Y + j) = d;
  verts(3u * Y + j1) = pt;
  verts(3u * Y + j2) = a;
  nbrs(3u * Y + j) = NBR(t, k);
  nbrs(3u * Y + j1) = sn1;
  nbrs(3u * Y + j2) = NBR(s, j1);
  info[t] = NBR(X, i1);
  info[s] = NBR(Y, j1);
}
#endif

#ifdef DT_INSERT_FIX
// The flip-list entries of e that are not DT_NONE, packed to the front; returns how many.
uint dt_pack_entries(inout uvec4 e) {
  uint count = 0u;
  for (uint k = 0u; k < 4u; ++k)
    if (e[k] != DT_NONE) e[count++] = e[k];
  return count;
}

// Writes the `count` packed entries of e to flip list 0 from position `at` (a list overflow is counted: a bug).
void dt_list_entries(uint at, uint count, uvec4 e) {
  if (count == 0u) return;
  if (at + count > p.capacity) {
    atomicAdd(counters[DT_OVERFLOW], 1u);
    return;
  }
  for (uint k = 0u; k < count; ++k) flip_list[at + k] = e[k];
}

// The round's splits are done and listed, n entries in flip list 0: the first flip pass's dispatch size and
// count; list 1, the bid list and the exact lists emptied for their next use. One invocation, last.
void dt_round_listed(uint n) {
  dt_write_list_args(0u, n);
  counters[DT_COUNT_LIST1] = 0u;
  counters[DT_BIDS] = 0u;
  counters[DT_EXACT_RELOC] = 0u;
  counters[DT_EXACT_FLIP] = 0u;
  if (n > 0u) counters[DT_FLIP_PASSES] += 1u;
}

// Slot t's bid: the split's repair if granted; returns its flip-list entries, 0..4 of e (DT_NONE: none).
uvec4 dt_fix_bid(uint t) {
  uint at = pickw[2u * t], sc = pickw[2u * t + 1u];
  pickw[2u * t] = DT_NONE;
  pickw[2u * t + 1u] = DT_NONE;
  if (!dt_granted(t)) return uvec4(DT_NONE);
  uint k = NBR_EDGE(loc[at]);
  loc[at] = DT_INSERTED | NBR(t, DT_INSIDE);  // t has the new vertex as a corner
  uint X = p.base + 2u * DT_SPLIT_NUMBER(t, at), Y = X + 1u;
  if (k == DT_INSIDE) {
    return uvec4(dt_fix_edge(t, 0u) ? DT_ENTRY(t, DT_CHECK_ONLY, 0u) : DT_NONE,
                 dt_fix_edge(X, 1u) ? DT_ENTRY(X, DT_CHECK_ONLY, 1u) : DT_NONE,
                 dt_fix_edge(Y, 2u) ? DT_ENTRY(Y, DT_CHECK_ONLY, 2u) : DT_NONE, DT_NONE);
  }
  // t = (c, a, p), X = (c, p, b), s = (d, b, p), Y = (d, p, a) (dt_split): the spokes are edges k + 1 of t,
  // k + 2 of X, j + 1 of s and j + 2 of Y; the halves of the split edge (t's and X's edge k) are checked
  // from t and X.
  uint s = NBR_TRI(sc), j = NBR_EDGE(sc);
  return uvec4(dt_entry_after(t, dt_next(k), dt_fix_edge(t, dt_prev(k)), true),
               dt_entry_after(X, dt_prev(k), true, dt_fix_edge(X, dt_next(k))),
               dt_entry_after(s, dt_next(j), dt_fix_edge(s, dt_prev(j)), false),
               dt_entry_after(Y, dt_prev(j), false, dt_fix_edge(Y, dt_next(j))));
}
#endif

#endif
