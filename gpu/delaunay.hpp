// The Delaunay triangulation of a canonical point set on the GPU, equal to CGAL's Delaunay_triangulation_2
// triangle for triangle: parallel insertion rounds (gDel2D-like) with exact flipping and CGAL's symbolic
// perturbation for co-circular points, a symbolic infinite vertex instead of a bounding triangle. The method
// and why it is exact: docs/gpu-delaunay.md.
//
//   gpu::DelaunayBuilder dt(ctx);                 // builds the passes once
//   gpu::GpuTriangulation tri = dt.build(xy);      // xy: canonical (sorted by x, then y, unique) pairs
//   Triangles tris = gpu::download_triangles(ctx, tri);
//
// Fewer than 3 points, or all points collinear: num_slots = 0 (no triangles), as CGAL has no finite faces
// then. Cost: about 20 rounds for 2M uniform points, each one submit with a host read of a few counters,
// plus a submit per further batch of flip passes. Device memory at the peak: 148.5 bytes per point (see
// peak_bytes()).
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/recorder.hpp"
#include "gpu/triangulation.hpp"
#include "gpu/voronoi_start.hpp"

namespace cdtgpu::gpu {

struct DelaunayStats {
  uint32_t rounds = 0;          // insertion rounds
  uint32_t flip_passes = 0;     // flip passes over a non-empty list
  uint32_t tail_passes = 0;     // of which run by a pass's last workgroup (DelaunayBuilder::tail_passes)
  uint32_t sampled_rounds = 0;  // rounds in which only the sample walked (DelaunayBuilder::sample_stride)
  uint32_t small_rounds = 0;    // rounds whose insertion steps ran in one workgroup (DelaunayBuilder::small_rounds)
  uint64_t flips = 0;
  uint64_t exact_walks = 0;                 // relocation walks the filters could not finish (exact pass)
  uint64_t exact_checks = 0;                // slot flip checks the filters could not decide (exact pass)
  uint32_t start_vertices = 0;              // vertices before the first round: 3, or the Voronoi start's
  VoronoiStats voronoi;                     // DelaunayBuilder::initial_dt voronoi: its sites, repairs, times
  std::vector<uint32_t> round_flip_passes;  // dispatched non-empty flip passes after each round's insertions
  // Per round: its GPU time (the relocate, insert and flip stages), the points it inserted, the flips after.
  struct Round {
    double ms = 0;
    uint32_t inserted = 0;
    uint64_t flips = 0;
  };
  std::vector<Round> round_log;
  // GPU time per stage (timestamps), summed over rounds, in order of first appearance: "start" (first
  // triangle, Morton order), "relocate" (walks + compaction), "insert" (pick, claim, split, fix), "flip"; with
  // the Voronoi start also "vd discretise", "vd flood", "vd dual", "vd repair (host)" and "vd flips".
  std::vector<std::pair<std::string, double>> stage_ms;
  uint64_t peak_device_bytes = 0;  // every buffer of the build alive at the peak, the result's included
  // With DelaunayBuilder::profile_kernels: every kernel in order, with its round and, for a flip pass, the
  // length of the list it read (else 0). Where the time goes, pass by pass.
  struct Kernel {
    uint32_t round;
    std::string name;
    double ms;
    uint32_t items;
  };
  std::vector<Kernel> kernel_log;
};

class DelaunayBuilder {
 public:
  explicit DelaunayBuilder(const Context& ctx);

  // Uploads the points and builds; the result owns them.
  GpuTriangulation build(std::span<const double> xy, DelaunayStats* stats = nullptr) const;
  // Builds on points already on the GPU (n canonical dvec2); takes the buffer over as the result's points.
  // `keep`: the triangulation's slots and the build's numbering taken from there (a caller gives the slots
  // back when done; tiles: one allocation a device instead of one a tile, whose driver calls serialise across
  // devices). Null: allocated here and freed with the result, the lower peak for one large run.
  GpuTriangulation build(Buffer points, uint32_t n, DelaunayStats* stats = nullptr, BufferCache* keep = nullptr) const;

  // Device bytes a build of n points holds at its peak (the same count as DelaunayStats::peak_device_bytes).
  static uint64_t peak_bytes(uint32_t n);

  const Context& context() const { return ctx_; }

  // Flip passes recorded blind (indirect dispatch over the current list): a round's first batch is as long as
  // the last round needed plus one (an empty pass still costs two dispatches, ~8 us on the H100); each
  // further batch (one submit each) is this long.
  uint32_t flip_passes_per_submit = 4;
  // With stats: time every kernel too (stages named "k:..."; the extra timestamps and barriers cost time).
  bool profile_kernels = false;
  // How flip checks reach the exact stage: `separate`, filters in one kernel and the undecided slots in a
  // second (an extra launch per flip pass); `inlined`, one kernel with the exact stage inline (fast while few
  // checks need it, slow when many do: grids); `adaptive`, inlined for a round when the last round needed the
  // exact stage for few slots. Default: adaptive on GPUs, separate on CPU devices (lavapipe runs the inlined
  // kernel several times slower). See docs/gpu-delaunay.md.
  enum class ExactChecks { separate, inlined, adaptive };
  ExactChecks exact_checks;
  // The last workgroup of each flip pass runs the following passes itself while the list is short
  // (dt_flip_tail: no launch and barrier per pass for the tail of a round). Its checks inline the exact
  // stage, so with ExactChecks::adaptive it is used in the rounds that inline them too (not on grids, where
  // one workgroup would run many exact checks). Default: on GPUs; on CPU devices the inlined exact stage
  // makes lavapipe's flip kernel slow.
  bool tail_passes;
  // Rounds that start with at most DT_SMALL_SLOTS slots in use run claim, grant, split and fix in one
  // workgroup of DT_SMALL_WG invocations (dt_insert_small) instead of five dispatches. Default: where the
  // device allows workgroups that large.
  bool small_rounds;
  // The first rounds, while there are few slots, let only every sample_stride-th point (in Morton order) walk
  // and bid, instead of relocating every point every round; then dt_hint starts the others' walks from a
  // sample point's slot. Builds of fewer than sample_min_points points (and a stride of 1) do not sample.
  uint32_t sample_stride = 32;
  uint32_t sample_min_points = 1u << 16;
  // Sample points left per slot in use below which the sampled rounds end. H100, stride x until, DT ms for 1M
  // / 2M / 4M uniform points: none 8.18 / 12.87 / 22.07; 32 x 2: 8.68 / 12.99 / 20.59; 32 x 8: 8.27 / 12.18 /
  // 19.78; 64 x 8: 8.59 / 12.01 / 20.30 (docs/gpu-delaunay.md).
  uint32_t sample_until = 8;
  // How the build starts: `insertion`, from one triangle (v0, v1 and the point farthest from their line);
  // `voronoi`, from the dual of a digital Voronoi diagram of the points on a grid (the paper's first step,
  // gpu/voronoi_start), flipped Delaunay before the rounds insert the points it lost. The result is the same.
  enum class Start { insertion, voronoi };
  Start initial_dt = Start::insertion;
  // Where the per-point and per-slot scratch comes from and goes back to (keys in gpu/buffers.hpp's
  // kPoints4 / kPoints16 / kSlots4 / kSlots8); null: allocated and freed by each build.
  BufferCache* cache = nullptr;

 private:
  struct State;
  bool first_triangle(State& st) const;
  void start(State& st) const;
  void voronoi_start(State& st) const;
  void insert_round(State& st) const;
  void flip_passes(State& st) const;
  void record_flip_batch(State& st, uint32_t passes, const char* stage = "flip") const;
  void scan(State& st, const Buffer& in, const Buffer& out, uint32_t n) const;
  void number_back(State& st) const;
  void submit(State& st, bool counters) const;
  Buffer scratch(const char* key, uint64_t bytes, const char* name) const;
  Buffer kept(State& st, const char* key, uint64_t bytes, const char* name = nullptr) const;
  void release(Buffer& b, const char* key) const;

  const Context& ctx_;
  Primitives prims_;
  Pass points_, init_, renumber_, hint_, number_back_, flags_, relocate_, relocate_exact_, compact_, claim_,
      grant_, rank_, split_, split_fix_, flip_check_, flip_check_exact_, flip_;
  // Variants queued where the defaults use them, else built on first use.
  mutable std::optional<Pass> flip_check_inline_, flip_tail_, insert_small_;
  mutable std::optional<VoronoiStarter> voronoi_;
  const Pass& insert_small() const;
  const Pass& flip_check_inline() const;
  const Pass& flip_tail() const;
};

GpuTriangulation build_delaunay(const Context& ctx, std::span<const double> xy,
                                DelaunayStats* stats = nullptr);

// Timing for the lead: `runs` builds of the same points; the median GPU milliseconds of every stage, then
// "gpu_total" (sum of the stages) and "wall" (host clock around build, upload excluded), each a median.
std::vector<std::pair<std::string, double>> bench_delaunay(const DelaunayBuilder& dt,
                                                           std::span<const double> xy, int runs);

}  // namespace cdtgpu::gpu
