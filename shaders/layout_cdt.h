// Constraint insertion and legalisation (gpu/constraints.cpp, shaders/cdt_*.comp), shared by C++ and GLSL:
// workgroup size, the crossed-edge record, the control block's word offsets and the push-constant blocks.
#ifndef CDTGPU_SHADERS_LAYOUT_CDT_H
#define CDTGPU_SHADERS_LAYOUT_CDT_H
#include "layout.h"

#ifdef __cplusplus
namespace cdtgpu::gpu::layout {
#endif

#define CDT_WG 64

// One row of the intersected-edge table: the i-th edge crossed by constraint `cons`, walking from its first
// vertex a to b. `edge` is NBR(slot, k): the edge opposite corner k of the triangle on a's side of it (T_{i-1};
// T_0 holds a). `info` holds the side of the apex w_i of the triangle beyond it (T_i) and the first-row flag.
struct CdtCross {
  uint edge;
  uint cons;
  uint info;
  uint flag;  // candidate this round (claims made): 1 removes a crossing, 2 keeps it; written by the claim pass
};
#define CDT_SIDE_MASK 3u
#define CDT_SIDE_LEFT 1u   // w_i is left of a->b
#define CDT_SIDE_RIGHT 2u  // w_i is right of a->b
#define CDT_SIDE_END 3u    // w_i is b: the last crossed edge
#define CDT_FIRST 4u       // i == 1: the apex on a's side is a itself

// Control block: one uint array; indirect-dispatch triples at offsets that are multiples of 4 bytes.
#define CDT_CTL_TOTAL 0u       // table rows to process this round (crossed edges; m * stride with fixed slots)
#define CDT_CTL_OVERFLOW 1u    // sticky 1: the table was too small in some round (that round flipped nothing)
#define CDT_CTL_FLIPS 2u       // flips this round (length of the flip list)
#define CDT_CTL_QUEUE 3u       // legalisation: slots in this round's queue
#define CDT_CTL_NEXT 4u        // legalisation: slots appended to the next queue
#define CDT_CTL_ERROR 5u       // first error code seen (CDT_ERR_*); 0 none
#define CDT_CTL_ERROR_CONS 6u  // the constraint the error is about
#define CDT_CTL_MAXK 7u        // sticky: the most edges one constraint crossed in any round
#define CDT_CTL_CROSSED 8u     // crossed edges found by this round's count walk (reset by CDT_ARGS_INSERT)
#define CDT_CTL_ROUND_OVER 9u  // fixed slots: a constraint crossed more edges than its rows this round
#define CDT_CTL_FIXES 10u      // outer edges of this round's cavities (length of the cavity fix list)
#define CDT_CTL_CAVITIES 11u   // constraints inserted by cavities this round
#define CDT_CTL_ARGS_TABLE 12u // dispatch over the table rows
#define CDT_CTL_ARGS_FLIPS 16u // dispatch over the flip list
#define CDT_CTL_ARGS_QUEUE 20u // dispatch over 3 x the queue (one invocation per slot edge)
#define CDT_CTL_ARGS_FIXES 24u // dispatch over the cavity fix list
#define CDT_CTL_WORDS 28u      // the words read back after each submission
// After them, with CdtWalkPush::through: the walks' (constraint, vertex) pairs of CDT_ERR_VERTEX_ON_CONSTRAINT, a
// count and then up to CDT_THROUGH_CAP pairs, so that a tile of an unresolved input can split those constraints
// (gpu/constraints.cpp; a count walk goes on past such a vertex and finds every one on its constraint).
#define CDT_CTL_THROUGH 28u
#define CDT_THROUGH_CAP 4096u
#define CDT_CTL_ALL_WORDS (CDT_CTL_THROUGH + 1u + 2u * CDT_THROUGH_CAP)
// Cavity insertion (cdt_cavity.comp): constraints crossing at most this many edges, owning them all.
#define CDT_CAVITY_MAX 8u

#define CDT_ERR_VERTEX_ON_CONSTRAINT 1u  // a walk met a vertex exactly on the open segment
#define CDT_ERR_LOST 2u                  // a walk could not find its start or ran past its step bound
#define CDT_ERR_NOT_AN_EDGE 3u           // marking: a constraint is not an edge after insertion
#define CDT_ERR_OUTSIDE 4u               // a constraint leaves the convex hull (met the infinite vertex)

// Walk modes.
#define CDT_WALK_INIT 0u   // start[c] = a slot holding a (from the vertex map)
#define CDT_WALK_COUNT 1u  // counts[c] = crossed edges (0 once c is an edge, whose bits it then sets); start[c] = T_0; with fixed
                           // slots (stride > 0) also writes the rows and claims, as WRITE does
#define CDT_WALK_WRITE 2u  // rows of c into table[offsets[c] ..] (from the row cache when they fit, else by
                           // walking again), owner claims on T_0 .. T_K
#define CDT_WALK_MARK 3u   // sets the constrained bit of the edge a-b on both sides (start from the vertex map);
                           // only after the host safety net rewrote slots

// Round numbers are global (insertion, then legalisation) and start at 1; stamp NEVER = never flipped.
#define CDT_NEVER 0xFFFFFFFFu

struct CdtWalkPush {
  uint m;          // constraints
  uint mode;       // CDT_WALK_*
  uint round;
  uint capacity;   // table rows available
  uint max_steps;  // bound on a walk's steps (a corrupt triangulation must not hang the device)
  uint stride;     // 0: prefix-sum layout (rows at offsets[c]); > 0: fixed slots, rows at c * stride
  uint cache;      // 1: COUNT keeps each constraint's rows (edge, info) in the row cache, and WRITE copies them
                   // instead of walking again when all of them fit (prefix-sum layout)
  uint domain;     // 1: claim T_0 .. T_K in owner[] (the influence-domain index); 0: ablation without it
  uint through;    // 1: a COUNT walk that meets vertices on its segment records them (CDT_CTL_THROUGH) and goes on
};

// Row cache: constraint c owns rows [cache_base[c] + CDT_CACHE_SLACK * c, + cache_cap[c] + CDT_CACHE_SLACK), laid
// out by the scan of the first count (a constraint rarely crosses more edges later than at first).
#define CDT_CACHE_SLACK 4u

struct CdtSlotsPush {
  uint n;      // slots (vertex map, legalisation seed) or unused
  uint round;
  uint all;    // legalisation seed: 1 = every finite slot, 0 = slots flipped during insertion
};

#define CDT_ARGS_INSERT 0u  // after the crossings are laid out: total rows, overflow check, table dispatch
#define CDT_ARGS_FLIPS 1u   // after a flip pass: dispatch over the flip list, per-round stats
#define CDT_ARGS_QUEUE 2u   // legalisation round start: next queue becomes the queue
struct CdtArgsPush {
  uint mode;
  uint m;          // constraints (CDT_ARGS_INSERT)
  uint capacity;   // table rows (CDT_ARGS_INSERT)
  uint round;
  uint stat_slot;  // index into the stats array (2 words per round: work items, flips)
  uint max_groups; // maxComputeWorkGroupCount[0]
  uint stride;     // fixed slots: rows per constraint (0: prefix-sum layout)
};

struct CdtRoundPush {
  uint round;
  uint one_per_constraint;  // ablation: a constraint flips at most one edge per round
  uint domain;              // 1: a flip needs its constraint to own both triangles; 0: ablation, claims alone
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
