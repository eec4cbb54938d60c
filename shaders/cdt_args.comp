// One invocation between passes: turns this round's counts into indirect-dispatch arguments and per-round
// statistics, so a whole batch of rounds runs in one command buffer without reading anything back.
//   CDT_ARGS_INSERT: after the crossings are laid out (scan of the per-constraint counts, or fixed slots): the
//                    rows to process; a table too small sets the sticky overflow flag and dispatches nothing
//                    (the host grows the table and the next round redoes the work).
//   CDT_ARGS_FLIPS:  after a flip pass: dispatch over the flip list for cdt_fix.
//   CDT_ARGS_QUEUE:  legalisation round start: the slots appended last round become this round's queue.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "layout_cdt.h"

layout(local_size_x = 1) in;
layout(std430, binding = 0) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 2) buffer Ctl { uint ctl[]; };
layout(std430, binding = 3) buffer Stats { uint stats[]; };
layout(push_constant) uniform Push { CdtArgsPush p; };

void set_args(uint at, uint items) {
  uint groups = (items + CDT_WG - 1u) / CDT_WG;
  uint x = min(groups, p.max_groups);
  ctl[at] = x;
  ctl[at + 1u] = x == 0u ? 1u : (groups + x - 1u) / x;
  ctl[at + 2u] = 1u;
}

void main() {
  if (p.mode == CDT_ARGS_INSERT) {
    uint crossed = ctl[CDT_CTL_CROSSED];
    uint total;
    bool over;
    if (p.stride > 0u) {  // fixed slots: every constraint's rows, empty or not
      total = crossed == 0u ? 0u : p.m * p.stride;
      over = ctl[CDT_CTL_ROUND_OVER] != 0u;
    } else {
      total = p.m == 0u ? 0u : offsets[p.m - 1u] + counts[p.m - 1u];
      over = total > p.capacity;
    }
    if (over) ctl[CDT_CTL_OVERFLOW] = 1u;
    ctl[CDT_CTL_TOTAL] = total;
    ctl[CDT_CTL_FLIPS] = 0u;
    ctl[CDT_CTL_FIXES] = 0u;
    ctl[CDT_CTL_CAVITIES] = 0u;
    ctl[CDT_CTL_CROSSED] = 0u;
    ctl[CDT_CTL_ROUND_OVER] = 0u;
    set_args(CDT_CTL_ARGS_TABLE, over ? 0u : total);
    stats[2u * p.stat_slot] = crossed;
    stats[2u * p.stat_slot + 1u] = over ? CDT_NEVER : 0u;  // CDT_NEVER: this round was skipped
  } else if (p.mode == CDT_ARGS_FLIPS) {
    set_args(CDT_CTL_ARGS_FLIPS, ctl[CDT_CTL_FLIPS]);
    set_args(CDT_CTL_ARGS_FIXES, ctl[CDT_CTL_FIXES]);
    // A constraint inserted by its cavity counts as a flip: the round made progress.
    if (stats[2u * p.stat_slot + 1u] != CDT_NEVER)
      stats[2u * p.stat_slot + 1u] = ctl[CDT_CTL_FLIPS] + ctl[CDT_CTL_CAVITIES];
  } else {
    uint q = ctl[CDT_CTL_NEXT];
    ctl[CDT_CTL_QUEUE] = q;
    ctl[CDT_CTL_NEXT] = 0u;
    ctl[CDT_CTL_FLIPS] = 0u;
    ctl[CDT_CTL_FIXES] = 0u;
    ctl[CDT_CTL_CAVITIES] = 0u;
    set_args(CDT_CTL_ARGS_QUEUE, 3u * q);
    stats[2u * p.stat_slot] = q;
    stats[2u * p.stat_slot + 1u] = 0u;
  }
}
