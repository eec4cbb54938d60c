// Workgroup size, counters and push constants of the Delaunay passes (gpu/delaunay.cpp, shaders/dt_*.comp),
// shared by C++ and GLSL. The method is in docs/gpu-delaunay.md.
#ifndef CDTGPU_SHADERS_LAYOUT_DT_H
#define CDTGPU_SHADERS_LAYOUT_DT_H
#include "layout.h"

#ifdef __cplusplus
namespace cdtgpu::gpu::layout {
#endif

#define DT_WG 256

// loc[p] with this bit: the point is a vertex already (the rest names a slot it is a corner of, or was when
// it was inserted: a place to start walks from for the points listed after it; see dt_hint).
#define DT_INSERTED 0x80000000u
// An empty flip-list entry; a slot not changed by the current step; a free pick or claim word.
#define DT_NONE 0xFFFFFFFFu
// loc[p] = NBR(slot, k): the uninserted point p lies in slot, strictly inside (k = DT_INSIDE) or on the
// relative interior of edge k.
#define DT_INSIDE 3u

// Flip-list entries: a slot (29 bits) and a code (3 bits) for which of its edges to check: mode * 3 + edge.
// Edges known to be locally Delaunay are not checked: the spokes of a split (the new edges at the inserted
// point) and the new diagonal of a flip (docs/gpu-delaunay.md). After a pass's checks every entry is a request
// or DT_NONE, so a request shares the code of "only edge k": the flip pass reads nothing else. 29 bits hold the
// slots of 2^28 points (two slots per point), the 3 bits every code; 2^29 - 1 would be DT_NONE.
#define DT_CHECK_ONLY 0u  // only edge k (each triangle of a 1->3 split: its one outer edge)
#define DT_CHECK_SKIP 1u  // all edges but k (a 2->4 spoke, a flip's new diagonal)
#define DT_CHECK_ALL 2u   // all edges (k = 0)
#define DT_REQUEST 0u     // written by the flip checks: the slot asks to flip its edge k
#define DT_ENTRY(slot, mode, k) (((slot) << 3) | ((mode)*3u + (k)))
#define DT_ENTRY_SLOT(e) ((e) >> 3)
#define DT_ENTRY_MODE(e) (((e)&7u) / 3u)
#define DT_ENTRY_EDGE(e) (((e)&7u) % 3u)
#define DT_MAX_SLOTS 0x1FFFFFFFu  // slot ids below this (DT_NONE is no valid entry)

// Words of the counters buffer. The two flip lists (0 and 1) alternate: a pass reads one and appends to the
// other. The exact lists hold the cases the floating-point filters left undecided (relocation walks, flip
// checks), for the exact pass that follows. Indirect-dispatch arguments live in a buffer of their own
// (DT_ARGS_*, three words each), so that no pass binds as storage the buffer its dispatch size is read from.
#define DT_COUNT_LIST0 0
#define DT_COUNT_LIST1 1
#define DT_EXACT_RELOC 2    // walks handed to dt_relocate_exact this round
#define DT_EXACT_FLIP 3     // slots handed to dt_flip_check_exact this pass
#define DT_WINNERS 4        // insertions of the current round
#define DT_FLIPS 5          // flips so far
#define DT_FLIP_PASSES 6    // flip passes that had a non-empty list
#define DT_NONCONVEX 7      // illegal edges whose quad was not strictly convex (never flipped; must stay 0)
#define DT_WALK_FAIL 8      // relocation walks that hit the step cap (must stay 0)
#define DT_OVERFLOW 9       // appends past a list's capacity (must stay 0)
#define DT_BEYOND 10        // an apex between the ends of a hull edge (theory says never; must stay 0)
#define DT_EXACT_WALKS 11   // all walks so far that needed the exact pass
#define DT_EXACT_CHECKS 12  // all slot checks so far that needed the exact pass
#define DT_DONE 13          // workgroups of the current dispatch that have finished (dt_last_group)
#define DT_TAIL_DONE 14     // flip passes run by dt_flip_tail's last workgroup so far (of DT_FLIP_PASSES)
#define DT_BIDS 15          // slots with a bid this round (the bid list: claim, grant, split, fix run over it)
#define DT_ARGS_LIST0 0
#define DT_ARGS_LIST1 3
#define DT_ARGS_RELOC 6
#define DT_ARGS_FLIP 9
#define DT_ARGS_BIDS 12
#define DT_ARGS_WORDS 15
#define DT_COUNTERS 16

// dt_flip_tail: the last workgroup of a flip pass runs up to DT_TAIL_PASSES further passes itself while the
// list holds at most DT_TAIL_MAX entries. Each of its passes uses the claim epoch p.epoch + pass, so the host
// steps the epoch by DT_TAIL_PASSES + 1 per pass.
#define DT_TAIL_MAX 512u
#define DT_TAIL_PASSES 64u

// dt_insert_small: an insertion round's claim, grant, split and fix in one workgroup while at most this many
// slots are in use (the first rounds: a bid per slot at most, one per invocation; the granted bits fit 32 words).
#define DT_SMALL_SLOTS 1024u
#define DT_SMALL_WG 1024

// dt_points: the y range (orderable 64-bit keys) and the point farthest from the line v0-v1.
struct DtPointsPush {
  uint n;
  uint v0;
  uint v1;
};

// dt_init: the first triangle (a, b, c), counter-clockwise, in slots 0..3; every point's loc, Morton key, id.
struct DtInitPush {
  uint n;
  uint a;
  uint b;
  uint c;
  uint key_shift;  // dt_init: the Morton keys' low bits dropped (DelaunayBuilder::start)
};

// Passes of an insertion round: over the point list (dt_relocate, dt_compact: n = its length) or over the
// slots in use (dt_claim, dt_grant, dt_split, dt_split_fix: n = base).
struct DtRoundPush {
  uint n;
  uint base;       // slots in use before this round: the first new slot of the round
  uint max_steps;  // relocation walk cap
  uint capacity;   // flip-list capacity (slots)
  uint round;      // insertion round, from 0
  uint epoch;      // this round's claim epoch (dt_claim_key)
  uint stride;     // dt_relocate, dt_hint: list positions from one walking point to the next (0 or 1: all)
  // dt_relocate(_exact): the first triangle's corners (x0, y0, x1, y1, x2, y2), whose centroid splits the
  // outside of the hull into one cone per hull edge (dt_walk)
  double corners[6];
};

// Flip passes: read list `src`, append to list 1 - src.
struct DtFlipPush {
  uint src;
  uint capacity;
  uint epoch;  // this pass's claim epoch (dt_claim_key)
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
