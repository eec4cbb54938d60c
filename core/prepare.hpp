// From what was read to what is triangulated: unique vertices and constraint segments by index.
#pragma once
#include <functional>
#include <span>

#include "core/model.hpp"

namespace cdtgpu {

struct PreparedInput {
  // Unique by (x, y), sorted lexicographically by (x, y). z of a merged vertex: the z of its first
  // occurrence in the order InputSet holds them: every loose point (in.points, in order) before every
  // polyline vertex (in.lines in order, each line's points in order). With several files this is not read
  // order: a later file's loose points come before an earlier file's lines.
  Points vertices;
  // Constraint segments (a < b), unique, no zero-length ones, sorted. Crossings are not resolved here.
  std::vector<Edge> constraints;
  // For each constraint, the index of the input polyline it came from (first one if shared). Unzeroed storage:
  // prepare writes every element on all cores (1 GB at 250M segments, which std::vector zeroed on one core first).
  RawVector<uint32_t> constraint_line;

  uint64_t input_points = 0;        // every vertex read (loose points and polyline vertices)
  uint64_t merged_duplicates = 0;   // input_points - vertices.size()
  uint64_t z_conflicts = 0;         // merged vertices whose z values differed
  double max_z_conflict = 0;        // largest |dz| among them
  uint64_t input_segments = 0;      // segments of all polylines and rings
  uint64_t duplicate_segments = 0;  // segments equal to an earlier one (shared ring edges, repeated lines)
  // Segments whose two ends are one vertex; add_polyline removes them, so only hand-built lines have any.
  uint64_t zero_length_segments = 0;
};

// Exact duplicate merging of n points (xy = x0, y0, x1, y1, ...): vertices numbered in (x, y) order,
// vertex_of[i] = the vertex of point i, first[v] = the smallest i on vertex v (-0.0 equals +0.0).
struct PointMerge {
  RawVector<uint32_t> vertex_of, first;
};
using PointMerger = std::function<PointMerge(std::span<const double> xy)>;

// On the CPU (core/merge_points.cpp): a bucket sort on all cores. gpu::merge_points (gpu/dedupe.hpp) gives the same on the GPU.
PointMerge merge_points(std::span<const double> xy);

// prepare's own merge (core/merge_points.cpp): merge_points of every occurrence in `in` (its points, then its
// lines' points), read where they are, with the merged vertices (the first occurrence's x, y and z) and the z
// conflicts made from the sorted occurrences. The vertex of each line point only (line_vertex_of[i]: of
// occurrence in.points.size() + i): loose points make no segments, and writing theirs was a random store each
// (1B at 1B points). `scattered` is called once `in`'s points are read no more.
struct MergedInput {
  RawVector<uint32_t> line_vertex_of;
  Points vertices;
  uint64_t z_conflicts = 0;
  double max_z_conflict = 0;
};
MergedInput merge_input(const InputSet& in, const std::function<void()>& scattered = {});

// `merge` does the duplicate merging, everything else (z of merged vertices, conflicts, segments) is then here;
// without one, merge_input does it all on the CPU, reading the input where it is. `gathered`, if given, is
// called once every coordinate has been read out of `in`: from then on only the number of lines and their
// sizes (taken before) are used, so the caller may free the points there, which keeps the input out of the
// merge's peak (24 of ~80 bytes a point).
//
// `ahead.made`, if given, is shown the vertices as soon as they are final, before the segments are made (the CLI
// begins writing the mesh file's vertex section there); if prepare throws after that, `ahead.abandoned` is called
// before the vertices are freed.
struct VerticesAhead {
  std::function<void(const Points& vertices)> made;
  std::function<void()> abandoned;
};
PreparedInput prepare(const InputSet& in, const PointMerger& merge = {},
                      const std::function<void()>& gathered = {}, const VerticesAhead& ahead = {});

}  // namespace cdtgpu
