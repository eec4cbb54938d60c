// Insertion round, step 1, over the point list: every point that is not a vertex yet walks from its old slot
// (slot ids stay valid through splits and flips) to the slot that contains it (dt_walk, floating-point filters
// only), then bids to be that slot's next vertex: a 64-bit atomicMin of (dt_bid_key << 32 | i) on pick[slot],
// i the point's position in the list (Morton order: the round's splits are numbered in that order, so new
// slots that lie together get ids that lie together); the smallest key wins, ties the smallest position.
// Lanes of a subgroup that bid on one slot (common: the list is in Morton order, and the first rounds have few
// slots) combine their bids first: one atomic per subgroup. A walk a filter cannot finish goes to the exact
// list (its position; dt_relocate_exact finishes it and bids). loc is kept per list position (coalesced here).
// A slot's first bid lists the slot (the bid list). The last workgroup sizes the exact pass. In the first
// rounds only every p.stride-th position walks (a sample; DelaunayBuilder::sample_stride).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "layout_dt.h"
#include "common.glsl"

#include "tri_refs.glsl"
layout(local_size_x = DT_WG) in;
layout(std430, binding = 0) readonly buffer Points { dvec2 xy[]; };
layout(std430, binding = 1) restrict readonly buffer VertsAt { TriWordsR verts_at; };
#define verts(i) TRI_WORD(TriWordsR, verts_at, i)
layout(std430, binding = 2) restrict readonly buffer NbrsAt { TriWordsR nbrs_at; };
#define nbrs(i) TRI_WORD(TriWordsR, nbrs_at, i)
layout(std430, binding = 3) buffer Loc { uint loc[]; };
layout(std430, binding = 4) readonly buffer List { uint list[]; };
layout(std430, binding = 5) buffer Pick { uint64_t pick[]; };
layout(std430, binding = 6) writeonly buffer Exact { uint exact_list[]; };
layout(std430, binding = 7) buffer Counters { uint counters[]; };
layout(std430, binding = 8) writeonly buffer Args { uint args[]; };
layout(std430, binding = 9) writeonly buffer Bids { uint bid_list[]; };
layout(push_constant) uniform Push { DtRoundPush p; };

#define DT_EXACT 0
#define DT_WALK
#define DT_APPEND
#define DT_LAST_GROUP
#include "dt_common.glsl"

void main() {
  uint i = (linear_group_id() * DT_WG + gl_LocalInvocationIndex) * max(p.stride, 1u);
  bool bids = false, undecided = false;
  uint t = DT_NONE, key = DT_NONE, pt = DT_NONE;
  if (i < p.n) {
    uint code = loc[i];
    if ((code & DT_INSERTED) == 0u) {
      pt = list[i];
      dvec2 q = xy[pt];
      code = dt_walk(NBR_TRI(code), q, p.max_steps, undecided);
      loc[i] = code;
      if (!undecided) {
        t = NBR_TRI(code);
        key = dt_bid_key(code, q);
        bids = true;
      }
    }
  }
  uint at = dt_append_base(DT_EXACT_RELOC, undecided ? 1u : 0u);
  if (undecided) exact_list[at] = i;
  // One bid per subgroup when every bidding lane bids on the same slot.
  uint t0 = subgroupMin(t);
  bool shared_slot = subgroupMin(bids && t != t0 ? 0u : 1u) == 1u;
  // The first bid on a slot (its pick word was free) lists the slot for this round's per-slot steps.
  uint first = 0u, slot = DT_NONE;
  if (shared_slot) {
    uint kmin = subgroupMin(key);
    uint pmin = subgroupMin(key == kmin ? i : DT_NONE);
    if (subgroupElect() && t0 != DT_NONE) {
      slot = t0;
      first = dt_bid(t0, (uint64_t(kmin) << 32) | uint64_t(pmin));
    }
  } else if (bids) {
    slot = t;
    first = dt_bid(t, (uint64_t(key) << 32) | uint64_t(i));
  }
  uint listed = dt_append_base(DT_BIDS, first);
  if (first == 1u) bid_list[listed] = slot;
  if (dt_last_group() && gl_LocalInvocationIndex == 0u) dt_write_args(DT_ARGS_RELOC, dt_count(DT_EXACT_RELOC));
}
