// Crossing detection by walking, one invocation per constraint (a, b). From a slot holding a it turns around a
// to the triangle T_0 whose corner at a holds the direction to b (or finds a-b as an edge), then walks across
// the edges the open segment crosses until it reaches b: e_1 .. e_K, triangles T_0 .. T_K. Modes (layout_cdt.h):
//   INIT   start[c] = vmap[a].
//   COUNT  counts[c] = K, start[c] = T_0; K = 0 and start[c] = CDT_NEVER once a-b is an edge (c is done: no
//          other constraint crosses it, so nothing flips it away), and then the edge's constrained bits are set
//          (they travel with the edge through the legalising flips). A start slot flipped last round no longer
//          holding a is replaced by its flip partner, which then does. With fixed slots (the ablation without
//          the prefix-sum layout) it also writes the rows, at c * stride, and empties the rest of c's rows.
//   WRITE  the K rows of c into table[offsets[c] ..] (the dynamic intersected-edge table) and the claims of c
//          on T_0 .. T_K in owner[] (the influence-domain index: the smallest constraint owns a triangle). The
//          COUNT walk kept the rows in the row cache; when all K fit they are copied (no predicates, no chain of
//          dependent loads), otherwise c walks again.
//   MARK   (after the host safety net, from a fresh vertex map) sets the constrained bits of edge a-b again.
// Every geometric question is orient2d(a, q, r) at one call site (lavapipe compiles each site separately).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "layout_cdt.h"
#include "common.glsl"
#include "subgroup_append.glsl"
#include "predicates.glsl"
#include "cdt_common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = CDT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 pts[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 3) readonly buffer Cons { uvec2 cons[]; };
layout(std430, binding = 4) buffer Start { uint start[]; };
layout(std430, binding = 5) buffer Counts { uint counts[]; };
layout(std430, binding = 6) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 7) writeonly buffer Table { CdtCross table[]; };
layout(std430, binding = 8) buffer Owner { uint64_t owner[]; };
layout(std430, binding = 9) buffer CFlags { uint cflags[]; };
layout(std430, binding = 10) readonly buffer VMap { uint vmap[]; };
layout(std430, binding = 11) readonly buffer Partner { uint partner[]; };
layout(std430, binding = 12) buffer Ctl { uint ctl[]; };
layout(std430, binding = 13) buffer RowCache { uvec2 row_cache[]; };  // (edge, info) per row
layout(std430, binding = 14) readonly buffer CacheBase { uint cache_base[]; };
layout(std430, binding = 15) readonly buffer CacheCap { uint cache_cap[]; };
layout(push_constant) uniform Push { CdtWalkPush p; };

void report(uint code, uint what) {
  if (atomicCompSwap(ctl[CDT_CTL_ERROR], 0u, code) == 0u) ctl[CDT_CTL_ERROR_CONS] = what;
}

// Vertex v lies on c's open segment: the error, and the pair for a caller that splits c there.
void through(uint c, uint v) {
  report(CDT_ERR_VERTEX_ON_CONSTRAINT, c);
  if (p.through == 0u) return;
  uint i = atomicAdd(ctl[CDT_CTL_THROUGH], 1u);
  if (i < CDT_THROUGH_CAP) {
    ctl[CDT_CTL_THROUGH + 1u + 2u * i] = c;
    ctl[CDT_CTL_THROUGH + 2u + 2u * i] = v;
  }
}

uint corner_of(uint t, uint v) {
  if (verts(3u * t) == v) return 0u;
  if (verts(3u * t + 1u) == v) return 1u;
  if (verts(3u * t + 2u) == v) return 2u;
  return 3u;
}

// The constrained bit of edge k of slot t, on both of its sides.
void mark_edge(uint t, uint k) {
  uint code = nbrs(3u * t + k);
  atomicOr(cflags[t], 1u << k);
  atomicOr(cflags[NBR_TRI(code)], 1u << NBR_EDGE(code));
}

// q on the line a-b (orient2d 0) and on b's side of a: q lies inside the segment, since b cannot lie inside
// the edge a-q of a triangulation. Comparisons only: exact.
bool on_b_side(dvec2 a, dvec2 q, dvec2 b) {
  return b.x != a.x ? (q.x > a.x) == (b.x > a.x) : (q.y > a.y) == (b.y > a.y);
}

#define ASK_V1 0u    // orient(a, v1, b) of the current corner at a
#define ASK_V2 1u    // orient(a, v2, b)
#define ASK_APEX 2u  // orient(a, b, w) of the apex beyond the crossed edge

#define FOUND_NONE 0u
#define FOUND_EDGE 1u     // a-b is the edge (t, k)
#define FOUND_CROSSED 2u  // walked to b, `rows` crossings
#define FOUND_ERROR 3u

void main() {
  uint c = linear_group_id() * CDT_WG + gl_LocalInvocationIndex;
  if (c >= p.m) return;
  uint a = cons[c].x, b = cons[c].y;
  if (p.mode == CDT_WALK_INIT) {
    start[c] = a == b ? CDT_NEVER : vmap[a];
    counts[c] = 0u;
    return;
  }
  uint t;
  if (p.mode == CDT_WALK_COUNT) {
    t = start[c];
    if (t == CDT_NEVER) {
      counts[c] = 0u;
      return;
    }
    if (corner_of(t, a) == 3u) {  // rewritten last round: by a flip (its partner holds a) or a cavity (vmap)
      uint q = partner[t];
      t = q != CDT_NEVER && corner_of(q, a) != 3u ? q : vmap[a];
    }
  } else if (p.mode == CDT_WALK_WRITE) {
    t = start[c];
    uint k_rows = counts[c];
    if (t == CDT_NEVER || k_rows == 0u || ctl[CDT_CTL_TOTAL] > p.capacity) return;
    uint cbase = cache_base[c] + CDT_CACHE_SLACK * c;
    if (p.cache != 0u && k_rows <= cache_cap[c] + CDT_CACHE_SLACK) {
      uint base = offsets[c];
      uint64_t okey = cdt_owner_key(p.round, c);
      uvec2 row = uvec2(0u);
      for (uint i = 0u; i < k_rows; ++i) {
        row = row_cache[cbase + i];
        table[base + i] = CdtCross(row.x, c, row.y, 0u);
        if (p.domain != 0u) atomicMin(owner[NBR_TRI(row.x)], okey);
      }
      if (p.domain != 0u) atomicMin(owner[NBR_TRI(nbrs(3u * NBR_TRI(row.x) + NBR_EDGE(row.x)))], okey);  // T_K
      return;
    }
  } else {
    t = vmap[a];
  }
  uint k = corner_of(t, a);
  if (k == 3u) {
    report(CDT_ERR_LOST, c);
    if (p.mode == CDT_WALK_COUNT) {
      counts[c] = 0u;
      start[c] = CDT_NEVER;
    }
    return;
  }

  dvec2 pa = pts[a], pb = pts[b];
  bool walking = p.mode == CDT_WALK_WRITE;  // WRITE starts at T_0, found by this round's COUNT
  uint t0 = t;
  uint ke = k;  // walking: the crossed edge is edge ke of slot t (t is T_{i-1})
  int o1 = 2, o2 = 2;  // rotating: orientations of the corner's two other vertices; 2 = not asked yet
  uint u = 0u, ku = 0u;  // walking: the slot beyond the crossed edge and the apex's corner in it
  uint rows = 0u;
  bool fixed_rows = p.mode == CDT_WALK_COUNT && p.stride > 0u;
  bool caching = p.mode == CDT_WALK_COUNT && p.stride == 0u && p.cache != 0u;
  uint cbase = caching ? cache_base[c] + CDT_CACHE_SLACK * c : 0u;
  uint ccap = caching ? cache_cap[c] + CDT_CACHE_SLACK : 0u;
  bool writing = p.mode == CDT_WALK_WRITE || fixed_rows;
  uint base = fixed_rows ? c * p.stride : (p.mode == CDT_WALK_WRITE ? offsets[c] : 0u);
  uint limit = fixed_rows ? p.stride : (p.mode == CDT_WALK_WRITE ? counts[c] : 0u);
  uint64_t okey = cdt_owner_key(p.round, c);
  uint found = FOUND_NONE;
  uint edge_t = 0u, edge_k = 0u;
  // COUNT with p.through: the segment passed through a vertex, and the walk goes on from there to find the others
  // on it (a caller splitting constraints gets them all from one walk); the count is then an error.
  bool broken = false;
  for (uint step = 0u; found == FOUND_NONE; ++step) {
    if (step > p.max_steps) {
      report(CDT_ERR_LOST, c);
      found = FOUND_ERROR;
      break;
    }
    dvec2 q, r;
    uint ask, asked;  // asked: the vertex at q (rotating) or r (walking)
    if (!walking) {
      uint v1 = verts(3u * t + cdt_next(k)), v2 = verts(3u * t + cdt_prev(k));
      if (v1 == b || v2 == b) {
        edge_t = t;
        edge_k = v1 == b ? cdt_prev(k) : cdt_next(k);
        found = FOUND_EDGE;
        break;
      }
      bool decided = v1 == INF_VERTEX || v2 == INF_VERTEX || (o1 != 2 && o2 != 2);
      if (decided && v1 != INF_VERTEX && v2 != INF_VERTEX && o1 > 0 && o2 < 0) {
        // b lies strictly inside the corner at a: the segment leaves T_0 across the edge opposite a.
        if (p.mode == CDT_WALK_MARK) {
          report(CDT_ERR_NOT_AN_EDGE, c);
          found = FOUND_ERROR;
          break;
        }
        walking = true;
        t0 = t;
        ke = k;
        continue;
      }
      if (decided) {  // turn to the next triangle around a, across the edge a-v2
        uint code = nbrs(3u * t + cdt_next(k));
        t = NBR_TRI(code);
        k = cdt_next(NBR_EDGE(code));
        o1 = v2 == INF_VERTEX ? 2 : o2;
        o2 = 2;
        continue;
      }
      ask = o1 == 2 ? ASK_V1 : ASK_V2;
      asked = ask == ASK_V1 ? v1 : v2;
      q = pts[asked];
      r = pb;
    } else {
      uint code = nbrs(3u * t + ke);
      u = NBR_TRI(code);
      ku = NBR_EDGE(code);
      uint w = verts(3u * u + ku);
      if (w == INF_VERTEX) {
        report(CDT_ERR_OUTSIDE, c);
        found = FOUND_ERROR;
        break;
      }
      if (w == b) {
        ++rows;
        uint info = CDT_SIDE_END | (rows == 1u ? CDT_FIRST : 0u);
        if (writing && rows <= limit) {
          table[base + rows - 1u] = CdtCross(NBR(t, ke), c, info, 0u);
          if (p.domain != 0u) {
            atomicMin(owner[t], okey);
            atomicMin(owner[u], okey);
          }
        }
        if (caching && rows <= ccap) row_cache[cbase + rows - 1u] = uvec2(NBR(t, ke), info);
        found = FOUND_CROSSED;
        break;
      }
      ask = ASK_APEX;
      asked = w;
      q = pb;
      r = pts[w];
    }
    int s = pred_orient2d(pa, q, r);
    // A vertex on the open segment: the apex ahead, or a neighbour of a on b's side (turning around a would
    // never find b's corner). The caller must split the constraint there.
    if (s == 0 && (ask == ASK_APEX || on_b_side(pa, q, pb))) {
      through(c, asked);
      if (p.mode != CDT_WALK_COUNT || p.through == 0u) {
        found = FOUND_ERROR;
        break;
      }
      broken = true;  // on from that vertex: a corner of t, or the apex of u
      if (ask == ASK_APEX) {
        t = u;
        k = ku;
        walking = false;
      } else {
        k = corner_of(t, asked);
      }
      a = asked;
      pa = pts[a];
      o1 = 2;
      o2 = 2;
      rows = 0u;
      continue;
    }
    if (ask == ASK_V1) {
      o1 = s;
    } else if (ask == ASK_V2) {
      o2 = s;
    } else {
      ++rows;
      uint info = (s > 0 ? CDT_SIDE_LEFT : CDT_SIDE_RIGHT) | (rows == 1u ? CDT_FIRST : 0u);
      if (writing && rows <= limit) {
        table[base + rows - 1u] = CdtCross(NBR(t, ke), c, info, 0u);
        if (p.domain != 0u) atomicMin(owner[t], okey);
      }
      if (caching && rows <= ccap) row_cache[cbase + rows - 1u] = uvec2(NBR(t, ke), info);
      // Left apex w: the segment leaves across R-w, the edge opposite the old left vertex; right: across w-L.
      ke = s > 0 ? cdt_next(ku) : cdt_prev(ku);
      t = u;
    }
  }

  if (broken) found = FOUND_ERROR;
  if (p.mode == CDT_WALK_COUNT) {
    uint crossed = found == FOUND_CROSSED ? rows : 0u;
    counts[c] = crossed;
    start[c] = found == FOUND_CROSSED ? t0 : CDT_NEVER;
    if (found == FOUND_EDGE) mark_edge(edge_t, edge_k);
    SUBGROUP_ADD(ctl[CDT_CTL_CROSSED], crossed);
    uint most = subgroupMax(crossed);
    if (subgroupElect() && most != 0u) atomicMax(ctl[CDT_CTL_MAXK], most);
    if (fixed_rows) {
      if (crossed > p.stride) ctl[CDT_CTL_ROUND_OVER] = 1u;
      for (uint i = min(crossed, p.stride); i < p.stride; ++i)
        table[base + i] = CdtCross(CDT_NEVER, CDT_NEVER, 0u, 0u);
    }
  } else if (p.mode == CDT_WALK_WRITE) {
    if (rows != limit) report(CDT_ERR_LOST, c);
  } else if (p.mode == CDT_WALK_MARK && found == FOUND_EDGE) {
    mark_edge(edge_t, edge_k);
  }
}
