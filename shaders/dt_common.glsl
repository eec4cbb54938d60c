// Helpers of the Delaunay passes (shaders/dt_*.comp). Slots follow gpu/triangulation.hpp: edge k of a slot is
// opposite vertex k and runs from vertex k+1 to vertex k+2; INF_VERTEX is symbolic and never has coordinates.
//
// Always: corner arithmetic and order-preserving float keys. The rest is switched on by the including shader,
// after it has declared the buffers the code names:
//   DT_CLAIMS     dt_claim_key (push constant p.epoch, or DT_EPOCH): claims of one step.
//   DT_RANKS      dt_granted, dt_rank (granted, granted_at, ranks): which slots split this round and their
//                 numbers. DT_GRANTED: dt_granted alone (granted).
//   DT_FIX_EDGES  dt_fix_edge (verts, nbrs, claim, info, p.epoch, DT_RANKS): the neighbour repair after a
//                 round of splits.
//   DT_WALK       dt_walk, dt_bid_key, dt_bid (xy, verts, nbrs, counters, pick): the relocation walk and bid.
//   DT_CHECK      dt_check_slot (xy, verts, nbrs, counters): the flip test of a slot's edges.
//   DT_APPEND     dt_append_base, dt_count_add (counters): workgroup-aggregated list appends and counts.
//   DT_LAST_GROUP dt_last_group, dt_write_args (counters, args): the last workgroup of a dispatch to finish
//                 sizes the next indirect dispatch, which saves a one-invocation dispatch (and its barrier) per
//                 step. DT_NO_ARGS: without the args writers (no args buffer).
// Predicates come in two builds of the same code: DT_EXACT 0 uses the floating-point filters alone and reports
// DT_UNDECIDED when a filter cannot decide; DT_EXACT 1 finishes those cases with the exact stage. The exact
// stage is big (private scratch arrays, expansion loops): inlined into the hot loop it made lavapipe 5-8x
// slower even when never reached, and it costs registers on any GPU. So the main passes are built without it
// and hand the rare undecided cases to a second, exact pass over a short list (docs/gpu-delaunay.md).
#ifndef CDTGPU_DT_COMMON_GLSL
#define CDTGPU_DT_COMMON_GLSL

uint dt_next(uint k) { return k == 2u ? 0u : k + 1u; }
uint dt_prev(uint k) { return k == 0u ? 2u : k - 1u; }

// Unsigned keys in the order of the floats they come from (negative floats below positive ones).
uint dt_orderable(float f) {
  uint u = floatBitsToUint(f);
  return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}

// The flip-list entry of slot s after a split or flip: edge `skip` is known to be legal, its other two edges
// are to be checked when `next` (edge skip + 1) and `prev` (edge skip - 1) say so; DT_NONE when neither is.
uint dt_entry_after(uint s, uint skip, bool next, bool prev) {
  if (next && prev) return DT_ENTRY(s, DT_CHECK_SKIP, skip);
  if (next || prev) return DT_ENTRY(s, DT_CHECK_ONLY, next ? dt_next(skip) : dt_prev(skip));
  return DT_NONE;
}

uint dt_inf_corner(uint v0, uint v1, uint v2) {
  return v0 == INF_VERTEX ? 0u : (v1 == INF_VERTEX ? 1u : (v2 == INF_VERTEX ? 2u : 3u));
}

#if defined(DT_WALK) || defined(DT_CHECK)
#ifdef DT_WALK
// Kind 2's points straight from the push constants: read where the filter needs them, not held in registers.
#define PRED_CORNER(k) dvec2(p.corners[2 * (k)], p.corners[2 * (k) + 1])
#endif
#include "predicates.glsl"
#define DT_UNDECIDED PRED_UNDECIDED

#if DT_EXACT
// The single exact-predicate site of a shader (lavapipe compiles every inlined site of pred_sign_of for
// seconds): kind 0 returns orient2d(p0, p1, p2), kind 2 orient2d(O, p0, p1) (dt_sign), kind 1 CGAL's
// side_of_oriented_circle(p0, p1, p2, p, perturb = true), i.e. pred_incircle_perturbed, whose steps this
// repeats exactly.
int dt_exact(int kind, dvec2 p0, dvec2 p1, dvec2 p2, dvec2 p) {
  if (kind != 1) return pred_sign_of(kind, p0, p1, p2, p2);
  dvec2 pts[4] = dvec2[4](p0, p1, p2, p);
  int order[4] = int[4](0, 1, 2, 3);
  for (int i = 1; i < 4; ++i) {
    int v = order[i];
    int j = i;
    while (j > 0) {
      dvec2 u = pts[order[j - 1]];
      bool less = pts[v].x < u.x || (pts[v].x == u.x && pts[v].y < u.y);
      if (!less) break;
      order[j] = order[j - 1];
      --j;
    }
    order[j] = v;
  }
  for (int step = 0; step < 4; ++step) {
    int k2 = 1;
    dvec2 a = p0, b = p1, c = p2;
    if (step > 0) {
      int k = order[4 - step];
      if (k == 3) return -1;
      k2 = 0;
      if (k == 0) a = p;
      if (k == 1) b = p;
      if (k == 2) c = p;
    }
    int s = pred_sign_of(k2, a, b, c, p);
    if (s != 0) return s;
  }
  return -1;
}
#endif

// kind 0: orient2d(a, b, c); kind 1: the perturbed incircle of (a, b, c) and d; kind 2: orient2d(O, a, b), O
// the centroid of the first triangle (DT_WALK shaders only; see pred_orient_sum_filter). The filter first (a
// non-zero incircle is also the perturbed answer: the perturbation only breaks ties); DT_UNDECIDED without
// DT_EXACT.
bool dt_used_exact = false;  // set when the exact stage ran (the inlined flip check counts its slots)

int dt_sign(int kind, dvec2 a, dvec2 b, dvec2 c, dvec2 d) {
  int s = pred_filter(kind, a, b, c, d);
  if (kind == 1 && s == 0) s = DT_UNDECIDED;
#if DT_EXACT
  if (s == DT_UNDECIDED) {
    dt_used_exact = true;
    s = dt_exact(kind, a, b, c, d);
  }
#endif
  return s;
}
#endif

#ifdef DT_WALK
// Visibility walk from slot t to the slot holding q, edges tried in order 0, 1, 2: it steps across the first
// edge that has q strictly on its far side. In a Delaunay triangulation such walks never cycle; the cap only
// guards against bugs. Outside the hull (convex whenever walks run: after a round's flips), the centroid O of
// the first triangle (strictly inside every later hull) splits the plane into one cone per hull edge x->y,
// between the rays from O through x (closed) and through y (open); the infinite slot (x, y, INF) holds the
// points of its cone strictly beyond x->y (orient2d(x, y, q) > 0). In an infinite slot the walk first moves
// along the hull to the cone of q (the neighbour sharing x while q is past the ray through x, the one sharing
// y while q is past the ray through y: both tests are exact, so it never turns back), then stops there if q is
// beyond the edge, else steps into the finite slot across it. The cones keep the triangles of one round's
// insertions outside the hull apart: a point merely beyond some hull edge could be split into one whose
// triangle overlaps another's. Returns NBR(slot, edge q lies on or DT_INSIDE); `undecided`: a filter could not
// decide (DT_EXACT 0 only), and the code is NBR(slot reached so far, DT_INSIDE), where the exact walk resumes.
uint dt_walk(uint t, dvec2 q, uint max_steps, out bool undecided) {
  uint k = 0u, on_edge = DT_INSIDE, steps = 0u, inf = 3u;
  undecided = false;
  uvec3 v, nb;
  dvec2 c0, c1, c2;
  bool enter = true;
  for (;;) {
    if (enter) {  // a new slot: its corners and neighbours in one round trip, the coordinates in a second
      v = uvec3(verts(3u * t), verts(3u * t + 1u), verts(3u * t + 2u));
      nb = uvec3(nbrs(3u * t), nbrs(3u * t + 1u), nbrs(3u * t + 2u));
      inf = dt_inf_corner(v.x, v.y, v.z);
      c0 = v.x == INF_VERTEX ? q : xy[v.x];
      c1 = v.y == INF_VERTEX ? q : xy[v.y];
      c2 = v.z == INF_VERTEX ? q : xy[v.z];
      enter = false;
    }
    // In an infinite slot, k counts its three tests: the ray through x, through y, then the hull edge x->y.
    uint e = inf < 3u ? inf : k;
    dvec2 a = e == 0u ? c1 : (e == 1u ? c2 : c0), b = e == 0u ? c2 : (e == 1u ? c0 : c1);
    bool ray = inf < 3u && k < 2u;
    int s = dt_sign(ray ? 2 : 0, ray && k == 1u ? b : a, ray ? q : b, q, q);  // one call site: less code
    if (s == DT_UNDECIDED) {
      undecided = true;
      on_edge = DT_INSIDE;
      break;
    }
    bool step;
    if (ray) {
      step = k == 0u ? s > 0 : s <= 0;  // past the ray through x: to the slot sharing x (across edge prev(inf))
      if (step) e = k == 0u ? dt_prev(inf) : dt_next(inf);
      ++k;
    } else if (inf < 3u) {
      if (s > 0) break;
      step = true;
    } else if (s < 0) {
      step = true;
    } else {
      if (s == 0) on_edge = e;
      ++k;
      if (k == 3u) break;
      step = false;
    }
    if (step) {
      t = NBR_TRI(e == 0u ? nb.x : (e == 1u ? nb.y : nb.z));
      k = 0u;
      on_edge = DT_INSIDE;
      enter = true;
      if (++steps > max_steps) {
        atomicAdd(counters[DT_WALK_FAIL], 1u);
        break;
      }
    }
  }
  return NBR(t, on_edge);
}

// The bid of a point at loc code `code` for its slot (smaller wins): in a finite slot the squared distance to
// the circumcentre (the point deepest in the slot's circle goes first: slivers break up early instead of
// keeping points, and their long relocation walks, for the last rounds), or to the centroid where the
// circumcentre lies on an edge (right triangles: grid DEMs) or far out (near-collinear slivers); for a point on
// an edge, to the edge's midpoint (points on lines and grid borders then split their edge in halves, not one by
// one); in an infinite slot the farthest beyond the hull edge wins (quickhull-like). Double estimates: the
// choice changes the work, never the result.
uint dt_bid_key(uint code, dvec2 q) {
  uint t = NBR_TRI(code), k = NBR_EDGE(code);
  uint v0 = verts(3u * t), v1 = verts(3u * t + 1u), v2 = verts(3u * t + 2u);
  uint inf = dt_inf_corner(v0, v1, v2);
  if (inf < 3u) {
    dvec2 x = xy[verts(3u * t + dt_next(inf))], y = xy[verts(3u * t + dt_prev(inf))];
    return dt_orderable(-float((y.x - x.x) * (q.y - x.y) - (y.y - x.y) * (q.x - x.x)));
  }
  dvec2 centre;
  if (k < 3u) {
    centre = (xy[verts(3u * t + dt_next(k))] + xy[verts(3u * t + dt_prev(k))]) * 0.5lf;
  } else {
    dvec2 a = xy[v0], b = xy[v1] - a, c = xy[v2] - a;
    double dd = 2.0lf * (b.x * c.y - b.y * c.x);
    double bb = dot(b, b), cc = dot(c, c);
    dvec2 o = dvec2(c.y * bb - b.y * cc, b.x * cc - c.x * bb) / dd;  // circumcentre - a
    // on an edge (a right triangle: every cell of a grid DEM) or far out (a sliver; also NaN, should the
    // determinant round to 0): the centroid, else the circumcentre
    double s0 = (b.x - o.x) * (c.y - o.y) - (b.y - o.y) * (c.x - o.x);
    double s1 = c.y * o.x - c.x * o.y, s2 = b.x * o.y - b.y * o.x;
    double tiny = 1e-6lf * abs(dd);
    bool on_edge = abs(s0) <= tiny || abs(s1) <= tiny || abs(s2) <= tiny;
    bool far = !(dot(o, o) <= 64.0lf * max(bb, max(cc, dot(c - b, c - b))));
    centre = a + (on_edge || far ? (b + c) / 3.0lf : o);
  }
  dvec2 d = q - centre;
  return dt_orderable(float(dot(d, d)));
}

// Bids `bid` on slot t (pick[t], 64-bit atomicMin); 1 when it was the slot's first bid. A plain read first
// skips the atomic of a bid that cannot win (the word only falls within a round, so a stale read costs at most
// an atomic): a slot's bidders queue on its word.
uint dt_bid(uint t, uint64_t bid) {
  uint64_t now = pick[t];
  if (now != ~uint64_t(0) && now <= bid) return 0u;
  return atomicMin(pick[t], bid) == ~uint64_t(0) ? 1u : 0u;
}
#endif

#ifdef DT_CHECK
bool dt_lex_less(dvec2 a, dvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// The first illegal edge of slot t among those `mode`/`m` ask for (DT_CHECK_*), in order 0, 1, 2, with u
// the neighbour across it:
//   INF is never inside a finite circle, and an edge of a finite and an infinite slot is a hull edge: legal.
//   Two infinite slots sharing the edge y-INF, t = (x, y, INF) and u with finite apex z: illegal iff
//     orient2d(x, y, z) > 0 (z strictly beyond the hull edge x->y: the hull is not convex at y).
//   Two finite slots: CGAL's perturbed incircle (side_of_oriented_circle(..., perturb = true)) > 0.
// An illegal finite edge must have a strictly convex quad (the flip's two triangles counter-clockwise); that is
// checked too, and a failure is counted and never flipped. Returns 1 (illegal: k and the neighbour code uc
// set), 0 (all legal) or DT_UNDECIDED (DT_EXACT 0: a filter could not decide before an illegal edge was found).
int dt_check_slot(uint t, uint mode, uint m, out uint k_out, out uint uc_out) {
  k_out = 0u;
  uc_out = 0u;
  for (uint k = 0u; k < 3u; ++k) {
    if ((mode == DT_CHECK_ONLY && k != m) || (mode == DT_CHECK_SKIP && k == m)) continue;
    uint c = verts(3u * t + k), a = verts(3u * t + dt_next(k)), b = verts(3u * t + dt_prev(k));
    uint uc = nbrs(3u * t + k);
    uint d = verts(3u * NBR_TRI(uc) + NBR_EDGE(uc));
    if (c == INF_VERTEX || d == INF_VERTEX) continue;
    bool finite = a != INF_VERTEX && b != INF_VERTEX;
    // (c, a, INF) has hull edge c->a; (c, INF, b) = (b, c, INF) has hull edge b->c.
    uint x = b == INF_VERTEX ? c : b, y = b == INF_VERTEX ? a : c;
    bool flip = true;
    for (int q = 0; q < 3; ++q) {
      int kind = 0;
      dvec2 p0, p1, p2;
      if (q == 0 && finite) {
        kind = 1;
        p0 = xy[c];
        p1 = xy[a];
        p2 = xy[b];
      } else if (q == 0) {
        p0 = xy[x];
        p1 = xy[y];
        p2 = xy[d];
      } else if (q == 1) {
        p0 = xy[c];
        p1 = xy[a];
        p2 = xy[d];
      } else {
        p0 = xy[d];
        p1 = xy[b];
        p2 = xy[c];
      }
      int s = dt_sign(kind, p0, p1, p2, xy[d]);
      if (s == DT_UNDECIDED) return DT_UNDECIDED;
      if (s <= 0) {
        if (q > 0) atomicAdd(counters[DT_NONCONVEX], 1u);
        if (q == 0 && !finite && s == 0 && (dt_lex_less(p0, p2) == dt_lex_less(p2, p1)))
          atomicAdd(counters[DT_BEYOND], 1u);
        flip = false;
        break;
      }
      if (!finite) break;
    }
    if (flip) {
      k_out = k;
      uc_out = uc;
      return 1;
    }
  }
  return 0;
}
#endif

#ifdef DT_APPEND
shared uint dt_sg_part[DT_WG];  // per subgroup: its total, then the workgroup's sum before it
shared uint dt_wg_base;

// Reserves `count` entries of the list counted by counters[word] for this invocation and returns the first:
// one atomicAdd per workgroup. Appends to one counter queue on one address; on the H100 one more atomic per
// subgroup on a counter cost dt_relocate ~27 us per round of 2M points. Call in uniform control flow (every
// invocation of the workgroup); count may be 0.
uint dt_append_base(uint word, uint count) {
  uint before = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  if (subgroupElect()) dt_sg_part[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint sum = 0u;
    for (uint s = 0u; s < gl_NumSubgroups; ++s) {
      uint x = dt_sg_part[s];
      dt_sg_part[s] = sum;
      sum += x;
    }
    dt_wg_base = sum > 0u ? atomicAdd(counters[word], sum) : 0u;
  }
  barrier();
  uint at = dt_wg_base + dt_sg_part[gl_SubgroupID] + before;
  barrier();  // both are reused by the next call
  return at;
}

// counters[word] += v, summed over the workgroup first (dt_append_base). Uniform control flow.
void dt_count_add(uint word, uint v) { dt_append_base(word, v); }
#endif

#ifdef DT_LAST_GROUP
shared bool dt_last_flag;

// Called by every invocation of the workgroup at the end of main (no early return before it): true in the
// one workgroup that finishes last, when every other workgroup's buffer writes are done. Counters written by
// other workgroups must then be read with atomics (dt_count).
bool dt_last_group() {
  memoryBarrierBuffer();
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint total = gl_NumWorkGroups.x * gl_NumWorkGroups.y * gl_NumWorkGroups.z;
    dt_last_flag = atomicAdd(counters[DT_DONE], 1u) == total - 1u;
    if (dt_last_flag) atomicExchange(counters[DT_DONE], 0u);
  }
  barrier();
  memoryBarrierBuffer();
  return dt_last_flag;
}

uint dt_count(uint word) { return atomicAdd(counters[word], 0u); }

#ifndef DT_NO_ARGS
// Indirect-dispatch arguments for `groups` workgroups, split over x and y like Recorder::dispatch_groups.
void dt_write_groups(uint at, uint groups) {
  uint x = min(groups, 65535u);
  args[at] = x;
  args[at + 1u] = x == 0u ? 1u : (groups + x - 1u) / x;
  args[at + 2u] = 1u;
}

// For n entries: at least one group, so that the dispatch's own last workgroup always runs.
void dt_write_args(uint at, uint n) { dt_write_groups(at, max((n + DT_WG - 1u) / DT_WG, 1u)); }

// For a flip list: no group at all when it is empty. A pass over an empty list has nothing to do, not even
// bookkeeping (its count is 0 and the other list's args are 0 groups too), so the passes recorded blind after a
// round's flips are done cost a barrier each, no launch.
void dt_write_list_args(uint list, uint n) {
  dt_write_groups(list == 0u ? DT_ARGS_LIST0 : DT_ARGS_LIST1, (n + DT_WG - 1u) / DT_WG);
}
#endif
#endif

#ifdef DT_CLAIMS
// Claims are 64-bit atomicMin words: (~epoch << 32) | priority, the priority being the requesting slot (splits)
// or NBR(slot, edge) (flips). Every step (a round's splits, each flip pass) has a new epoch, and a newer epoch's
// key is below every older one, so claims never need resetting: a claim word is current iff its high word is
// ~p.epoch, and a request won iff its key still stands on every slot it claimed.
#ifndef DT_EPOCH
#define DT_EPOCH p.epoch
#endif
uint64_t dt_claim_key(uint prio) { return (uint64_t(~DT_EPOCH) << 32) | uint64_t(prio); }
bool dt_claim_current(uint64_t c) { return uint(c >> 32) == ~DT_EPOCH; }

#if defined(DT_CHECK) && DT_EXACT
// A flip list entry's check with the exact stage inline (partner, claim): the slot's first illegal edge k is
// requested (partner[t] = the neighbour's code, both slots claimed with the priority NBR(t, k)); returns the
// entry's new value, DT_ENTRY(t, DT_REQUEST, k) or DT_NONE (locally Delaunay).
uint dt_request(uint entry) {
  uint t = DT_ENTRY_SLOT(entry);
  uint k, uc;
  if (dt_check_slot(t, DT_ENTRY_MODE(entry), DT_ENTRY_EDGE(entry), k, uc) != 1) return DT_NONE;
  partner[t] = uc;
  uint64_t key = dt_claim_key(NBR(t, k));
  atomicMin(claim[t], key);
  atomicMin(claim[NBR_TRI(uc)], key);
  return DT_ENTRY(t, DT_REQUEST, k);
}
#endif
#endif

#if defined(DT_RANKS) || defined(DT_GRANTED)
// The granted splits of a round (dt_grant): a bit per slot, and a bit per list position of the winning point,
// with the set bits before each 32-position word (shaders/dt_rank.comp: within its tile of DT_WG words, and
// per tile, after the p.n list positions' words and the total). A split's number is the rank of its point's
// position: the list is in Morton order, so the new slots of points that lie together get ids that lie
// together, and the flip passes' loads of neighbouring slots share cache lines.
bool dt_granted(uint t) { return ((granted[t >> 5u] >> (t & 31u)) & 1u) != 0u; }
#endif
#ifdef DT_RANKS
uint dt_split_count() { return ranks[(p.n + 31u) / 32u]; }
uint dt_rank(uint at) {
  uint w = at >> 5u, words = (p.n + 31u) / 32u;
  return ranks[words + 1u + w / DT_WG] + ranks[w] + bitCount(granted_at[w] & ((1u << (at & 31u)) - 1u));
}
#endif

#ifdef DT_FIX_EDGES
// After a round of splits: slot q's edge e faces the outside of its split. nbrs[3q+e] still holds the
// neighbour code from before. The neighbour u was split this round iff its current claim belongs to a granted
// split. If it was not, it is pointed back at (q, e); this is its only writer. If it was, its edge either stayed
// in place (same two vertices at the same index) or moved where info[u] says: NBR(X, 3) for a 1->3 split (edge
// l went to slot X + l - 1, same index; l = 0 stayed), else NBR(w, l') = "the edge that left went to slot w,
// index l'". The thread fixing u does the same from its side. Returns whether q's side checks the edge in the
// first flip pass: when u was split too, its side lists the edge as well, and the smaller slot checks it.
bool dt_split_this_round(uint u) {
  uint64_t c = claim[u];
  uint t = uint(c);
  return dt_claim_current(c) && dt_granted(t);
}

bool dt_fix_edge(uint q, uint e) {
  uint c = nbrs(3u * q + e);
  uint u = NBR_TRI(c), l = NBR_EDGE(c);
  if (!dt_split_this_round(u)) {
    nbrs(3u * u + l) = NBR(q, e);
    return true;
  }
  uint x = verts(3u * q + dt_next(e)), y = verts(3u * q + dt_prev(e));
  if (verts(3u * u + dt_next(l)) == y && verts(3u * u + dt_prev(l)) == x) return q < u;
  uint inf = info[u];
  uint f = NBR_EDGE(inf) == DT_INSIDE ? NBR(NBR_TRI(inf) + l - 1u, l) : inf;
  nbrs(3u * q + e) = f;
  return q < NBR_TRI(f);
}
#endif

#endif
