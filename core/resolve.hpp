// Turns prepared constraints into a clean planar straight-line graph: the input of backends (the GPU one)
// that triangulate the vertices first and then recover constraints by flipping, which needs constraints that
// never cross each other and never pass through a vertex.
#pragma once
#include <atomic>
#include <cstdint>
#include <vector>

#include "core/model.hpp"
#include "core/prepare.hpp"

namespace cdtgpu {

struct ResolvedInput {
  // prepared.vertices plus the Steiner vertices, canonical: sorted by (x, y), unique.
  Points vertices;
  // Segments (a < b), unique, sorted; no two cross, none has a vertex strictly inside it.
  std::vector<Edge> constraints;
  // Vertices created where constraints cross (same meaning as CdtResult::steiner_points); a crossing whose
  // rounded point is an existing vertex merges into it and is not counted.
  uint64_t steiner_points = 0;
  // Constraint pieces created because a segment passed exactly through an existing vertex (an input vertex,
  // or a Steiner vertex of an earlier round): one per such split.
  uint64_t split_at_vertices = 0;
  // resolve_if_needed: nothing was split, and vertices and constraints are left empty: the prepared ones are
  // the resolved input.
  bool unchanged = false;
};

// The rules of docs/rules.md ("Constraints"): a segment is split at every vertex exactly inside it; two
// segments that cross get a Steiner vertex at their exact crossing rounded to the nearest double (what
// triangulate_cgal computes), z interpolated along the lowest-indexed prepared constraint whose pieces end
// at it (triangulate_cgal's rule). A rounded Steiner vertex is generally just off both segments; both are
// split there anyway, each at all its vertices and crossings in the order of their exact positions along
// it, and the new pieces are checked again until nothing crosses and no vertex lies inside a piece.
// Collinear overlapping segments split at each other's ends and the equal pieces merge.
//
// `prepared` as prepare() makes it: vertices sorted by (x, y) and unique (relied on, not checked);
// constraints a < b and sorted (checked; another order costs a sort). Deterministic: the result does not
// depend on `threads` (0: std::thread::hardware_concurrency()) or on timing.
// Cost without crossings: one sweep over the vertices and constraints (core/resolve.cpp); 2M vertices and
// 500K non-crossing constraints take ~57 ms on 2 threads on the 2-core development machine, ~100 ms on 1.
// The first overload also copies the vertices (48 MB there; the copy overlaps the sweep when threads > 1,
// ~70 ms in all); the second takes them from `prepared` (its vertices and constraints are left empty).
ResolvedInput resolve_constraints(const PreparedInput& prepared, unsigned threads = 0);
ResolvedInput resolve_constraints(PreparedInput&& prepared, unsigned threads = 0);

// What a caller running resolve_constraints on another thread may learn early: after the first sweep (a
// fraction of the whole), whether constraints cross (Steiner vertices are coming). -1 until then.
struct ResolveProgress {
  std::atomic<int> crossings{-1};
};
ResolvedInput resolve_constraints(const PreparedInput& prepared, ResolveProgress& progress, unsigned threads = 0);

// resolve_constraints without copying a clean input: `unchanged` when nothing is split (the prepared vertices
// and constraints are the resolved input); the copy is made only when something is (at 1B points the copy was
// 24 bytes a vertex of the resolve's peak).
ResolvedInput resolve_if_needed(const PreparedInput& prepared, unsigned threads = 0);

}  // namespace cdtgpu
