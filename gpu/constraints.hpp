// Constraint insertion on the GPU (Chen, Kong, Chen, Song 2026, see docs/gpu-constraints.md): makes every
// constraint segment an edge of a Delaunay triangulation already on the GPU by edge flips, then restores the
// constrained Delaunay property by flipping. The result equals CGAL's Constrained_Delaunay_triangulation_2
// triangle for triangle (exact predicates, CGAL's symbolic perturbation for co-circular points).
//
//   gpu::Primitives prims(ctx);
//   gpu::ConstraintInserter inserter(ctx, prims);              // builds the pipelines once
//   gpu::GpuTriangulation tri = gpu::upload_triangulation(ctx, host_dt);
//   gpu::ConstraintStats stats;
//   gpu::ConstrainedEdges ce = inserter.insert(tri, constraints, &stats);
//   Triangles mesh = gpu::download_triangles(ctx, tri);
//
// Requirements on the input: `tri` holds the Delaunay triangulation of its points (the perturbed one, as CGAL
// builds it; set ConstraintOptions::legalise_all otherwise); constraints are pairs of vertex indices, inside the
// convex hull, that cross no other constraint and pass through no vertex (split them there first). Shared
// endpoints, repeated constraints and constraints that already are edges are fine. A violation is reported as a
// DeviceError naming the constraint.
//
// Cost per round: two walks per unfinished constraint (orient2d per crossed edge), a scan over the constraints,
// one light pass over the crossed edges; memory ~64 bytes per slot (2 slots per point), 20 bytes per
// constraint and 16 per crossed edge.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/triangulation.hpp"

namespace cdtgpu::gpu {

// Switches for the ablation of the paper's Table 3. Defaults are the full method.
struct ConstraintOptions {
  enum class Layout {
    PrefixSum,   // count, scan, write: the compact dynamic intersected-edge table
    FixedSlots,  // one walk writes into a fixed number of rows per constraint (the longest constraint's count)
  };
  enum class Flipping {
    Adaptive,       // every candidate edge of every constraint may flip each round
    OnePerConstraint,  // each constraint flips at most one edge per round
  };
  Layout layout = Layout::PrefixSum;
  Flipping flipping = Flipping::Adaptive;
  // The influence-domain index: each round the smallest constraint crossing a triangle owns it, and a flip runs
  // only inside its own constraint's domain, so it never disturbs a constraint of higher priority (progress).
  // false (ablation): no owners; conflicting flips are settled by the slot claims alone, and progress rests on
  // the claims' per-round hashed order and the stall safety net below.
  bool domain_index = true;
  // Cavity insertion (ours, beyond the paper): a constraint that crosses at most CDT_CAVITY_MAX edges and owns
  // all of its triangles this round is inserted at once by retriangulating its cavity; the rest go on by flips.
  // Needs the domain index and the prefix-sum layout; off in the paper's ablation variants.
  bool cavities = true;
  // Seed legalisation with every finite slot, not only the slots flipped during insertion: for inputs that are
  // not the (perturbed) Delaunay triangulation of their points.
  bool legalise_all = false;
  uint32_t rounds_per_submit = 8;  // rounds recorded into one command buffer before the counts are read
  // Safety net. Flips that keep a crossing have no known potential function, so flipping is not proven to end
  // (it ends in every test; the per-round hashed schedule keeps it from repeating itself). When the number of
  // crossed edges has not reached a new low for `stall_rounds` rounds, or after `flip_round_limit` rounds, the
  // constraints still crossing are inserted on the host, one at a time, by retriangulating their cavities
  // exactly (counted in ConstraintStats::fallback_constraints); legalisation then checks every slot.
  uint32_t stall_rounds = 256;
  uint32_t flip_round_limit = UINT32_MAX;
  uint32_t max_rounds = 1u << 20;  // legalisation beyond this many rounds is reported as an error
  // Timestamps around every kernel ("k:..." stages, summed over rounds) and every round ("r<N> insert",
  // "r<N> legalise"), in ConstraintStats::stage_ms. Their barriers add cost; for finding where time goes.
  bool profile_kernels = false;
  // The constraints are not resolved (a tile of an unresolved input, TileOptions::unresolved). A constraint
  // through vertices is split at them (ConstrainedEdges::split), as the resolve would. Anything else the resolve
  // would split makes one of the insertion's checks fail (a flip or cavity would remove a constrained edge,
  // marking after the safety net finds a constraint gone) or a round stall; any such failure is thrown as
  // UnresolvedTile (core/tiles.hpp). TooLarge and Vulkan errors stay.
  bool unresolved = false;
  // The caller knows the list is sorted (unresolved: a split's pieces are looked up in it; else it is read).
  bool sorted = false;
};

struct ConstraintStats {
  uint32_t flip_rounds = 0;      // insertion rounds that found crossed edges
  uint32_t legalise_rounds = 0;  // legalisation rounds with a non-empty queue
  uint64_t crossed_edges = 0;    // edges crossed by the constraints in the input triangulation
  uint32_t longest_crossing = 0;  // the most edges one constraint crosses in the input triangulation
  uint64_t insertion_flips = 0;      // flips, and constraints inserted by their cavities
  uint64_t legalise_flips = 0;
  uint32_t fallback_constraints = 0;  // inserted by the host safety net (see ConstraintOptions::stall_rounds)
  // Per insertion round: edges crossed at its start and flips made (UINT32_MAX: skipped, table grown).
  std::vector<std::array<uint32_t, 2>> rounds;
  // Per legalisation round: queued slots at its start and flips made.
  std::vector<std::array<uint32_t, 2>> legalise_log;
  std::vector<std::pair<std::string, double>> stage_ms;  // GPU time per stage, in pipeline order
  uint64_t peak_device_bytes = 0;  // the triangulation, the constrained bits and the inserter's scratch
};

// Which edges are constrained, kept on the GPU: bit k of flags[t] is set when the edge opposite corner k of
// slot t is a constraint (set on both sides of the edge). Valid for the slots of the triangulation it came from.
struct ConstrainedEdges {
  Buffer flags;
  uint32_t num_slots = 0;
  // ConstraintOptions::unresolved: each constraint (a, b) split at a vertex v exactly inside it, as (a, b, v), in
  // the order split (a piece of an earlier split may be split again). The edges inserted are the pieces.
  std::vector<std::array<uint32_t, 3>> split;
};

// Holds the pipelines, and the scratch buffers between calls (grown as needed; release() frees them). One call
// at a time per inserter.
class ConstraintInserter {
 public:
  ConstraintInserter(const Context& ctx, const Primitives& prims);
  ~ConstraintInserter();
  ConstraintInserter(const ConstraintInserter&) = delete;
  ConstraintInserter& operator=(const ConstraintInserter&) = delete;

  // Makes every constraint an edge of `tri`, then restores the constrained Delaunay property. Throws
  // DeviceError when a constraint breaks the input requirements (crossing, through a vertex, outside the hull),
  // except as ConstraintOptions::unresolved says. `uploaded`: the constraints copied to the device already
  // (8 bytes each, checked against the points; a tile's, gpu/cdt_pipeline), read and left as they are.
  ConstrainedEdges insert(GpuTriangulation& tri, std::span<const Edge> constraints, ConstraintStats* stats = nullptr,
                          const ConstraintOptions& options = {}, const Buffer* uploaded = nullptr) const;
  // Frees the scratch buffers kept since the last call.
  void release() const;
  // Puts a result's flags into `cache` for the next call's (tiles: 4 bytes a slot, 1 GB a tile at 1B points,
  // allocated and freed per tile otherwise). Without a cache they are freed.
  void recycle(ConstrainedEdges&& edges) const;

  // Where the scratch lives between calls; null: a cache of its own. Per-point and per-slot buffers use the
  // shared keys of gpu/buffers.hpp, so a cache shared with the Delaunay build reuses its buffers.
  BufferCache* cache = nullptr;

 private:
  struct Scratch;
  class EdgeList;
  // insert() of resolved constraints. split_through: walks that meet vertices on their constraints hand the
  // pairs back (as ThroughVertices, gpu/constraints.cpp) instead of an error.
  ConstrainedEdges insert_once(GpuTriangulation& tri, const EdgeList& constraints, ConstraintStats* stats,
                               const ConstraintOptions& options, bool split_through,
                               const Buffer* uploaded = nullptr) const;
  const Context& ctx_;
  const Primitives& prims_;
  mutable std::unique_ptr<Scratch> scratch_;
  Pass vertex_map_, walk_, args_, insert_claim_, insert_flip_, fix_, cavity_, cavity_fix_, legal_seed_, legal_claim_,
      legal_flip_;
};

// Throws std::invalid_argument naming the first constraint with a vertex index of num_points or more (insert's
// own check, which callers that upload the constraints themselves make beforehand).
void check_constraint_ids(std::span<const Edge> constraints, uint64_t num_points);

// One-shot convenience (builds the pipelines on every call; keep a ConstraintInserter for repeated use).
ConstrainedEdges insert_constraints(const Context& ctx, GpuTriangulation& tri, std::span<const Edge> constraints,
                                    ConstraintStats* stats = nullptr, const ConstraintOptions& options = {});

// The constrained edges as vertex pairs (smaller index first), sorted, each once.
std::vector<Edge> download_constrained_edges(const Context& ctx, const GpuTriangulation& tri,
                                             const ConstrainedEdges& edges);

}  // namespace cdtgpu::gpu
