// The whole GPU backend in one place: prepared input -> constrained Delaunay triangulation, equal to
// triangulate_cgal's result (same vertices, same triangles, same canonical order, same Steiner count).
//
//   gpu::Context ctx = gpu::create_context();
//   gpu::GpuCdt cdt(ctx);                       // builds every pipeline once
//   PreparedInput prepared = prepare(input, cdt.merger());   // duplicates merged on the GPU
//   gpu::GpuCdtStats stats;
//   CdtResult r = cdt.triangulate(prepared, &stats);
//
// Stages (gpu/cdt_pipeline.cpp reads as this list):
//   resolve      CPU, core/resolve: split constraints at vertices, Steiner vertices at crossings; on other
//                threads while the GPU builds the Delaunay triangulation (again after it where they cross)
//   delaunay     GPU, gpu/delaunay: Delaunay triangulation of all vertices (docs/gpu-delaunay.md)
//   constraints  GPU, gpu/constraints: the paper's insertion by flips, then legalisation (docs/gpu-constraints.md)
//   download     GPU: finite triangles sorted into canonical order (gpu/canonical), then to the host
#pragma once
#include <cstdint>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/tiles.hpp"
#include "gpu/canonical.hpp"
#include "gpu/constraints.hpp"
#include "gpu/context.hpp"
#include "gpu/dedupe.hpp"
#include "gpu/delaunay.hpp"
#include "gpu/primitives.hpp"
#include "gpu/tile_final.hpp"

namespace cdtgpu::gpu {

struct GpuCdtStats {
  // Host wall clock per stage ("upload", "delaunay", "resolve wait", "constraints", "download"), in order;
  // "upload" and "delaunay" twice when the Delaunay triangulation was built again.
  std::vector<std::pair<std::string, double>> wall_ms;
  // Device timestamps per GPU stage, "dt ..." then "cdt ...", in order; gpu_total_ms is their sum.
  std::vector<std::pair<std::string, double>> gpu_ms;
  double gpu_total_ms = 0;
  double wall_total_ms = 0;  // resolve to download, all included
  DelaunayStats delaunay;
  ConstraintStats constraints;
  uint64_t split_at_vertices = 0;
  // Constraints crossed, so the Delaunay triangulation built beside the resolve stage (on the prepared
  // vertices) was built again with the Steiner vertices; both builds are in the stages.
  bool delaunay_built_twice = false;
  // The most device memory held at once: the larger of the two GPU stages' own peaks, or what the pipeline holds
  // during the canonical sort (the triangulation and the shared scratch cache, which the sort draws on too).
  uint64_t peak_device_bytes = 0;
};

class GpuCdt {
 public:
  explicit GpuCdt(const Context& ctx);

  CdtResult triangulate(const PreparedInput& prepared, GpuCdtStats* stats = nullptr) const;
  // The same with the CPU's resolve stage already running (resolve_constraints(prepared) on other threads,
  // started as early as the caller likes: cdtgpu triangulate starts it while the device starts). The GPU builds
  // the Delaunay triangulation of the prepared vertices meanwhile. `prepared` must outlive the call.
  // With `progress` (the resolve's), the build waits for the resolve instead where it has found crossings.
  CdtResult triangulate(const PreparedInput& prepared, std::future<ResolvedInput> resolving,
                        GpuCdtStats* stats = nullptr, const ResolveProgress* progress = nullptr) const;

  // The CDT of a graph resolved already (vertices sorted and unique, segments meeting only at shared endpoints and
  // through no vertex: a tile of core/tiles): stages 2-4 without the resolve stage or any copy of the input.
  // Triangles in canonical order. Its buffers stay for the next call, as a tile's do (a merge after tiles).
  Triangles triangulate_graph(const Points& vertices, const std::vector<Edge>& segments,
                                          GpuCdtStats* stats = nullptr) const;

  // A tile of core/tiles (a resolved graph too, its vertices job.all[job.ids[i]]): stages 2-3, then its final
  // triangles and their border found on the device (gpu/tile_final) and only those downloaded, sorted.
  TileFinal finalize_tile(const TileJob& job, GpuCdtStats* stats = nullptr) const;
  // The same in parts, so that tiles in flight hold the device only for its own part (gpu/tile_triangulator):
  // the tile's points written into `staging` (host work; staging_bytes of it); uploaded on the copy queue
  // (Context::copy_queue); the device's part, which leaves the sorted final triangles in `sorted` and returns
  // their count (the border in `f`); those downloaded into `staging` on the copy queue; then copied out (host
  // work). One tile's copies run beside another's compute: a tile of 125M points moves 2 GB up and 3 GB down,
  // ~0.2 s of its 0.7 s device call at 1B points. Stage times are added to `s`.
  //
  // The tile's segments go the same way, behind its points in the staging buffer where they fit (no more segments
  // than points): uploaded inside the device's hold, they took 20 ms of a 1B-point tile's call on one device and
  // 50 ms on each of two, the copy on all cores meeting the other tile's host copies.
  static uint64_t staging_bytes(uint64_t vertices);  // a tile of this many vertices
  // Returns whether the staged segments are sorted (read as they are copied; ConstraintOptions::sorted).
  static bool stage_points(const TileJob& job, HostStaging& staging);
  struct TileUpload {
    Buffer points;
    Buffer segments;  // none where they did not fit (compute_tile uploads them itself)
    bool segments_sorted = false;  // stage_points' answer
  };
  TileUpload upload_tile(const TileJob& job, const HostStaging& staging, GpuCdtStats& s) const;
  uint32_t compute_tile(const TileJob& job, TileUpload up, HostStaging& staging, TileFinal& f, Buffer& sorted,
                        GpuCdtStats& s) const;
  void download_tile(Buffer sorted, uint32_t count, const HostStaging& staging, GpuCdtStats& s) const;
  // The tile's `count` final triangles from `staging` into f, its border (as the device left it) sorted beside.
  static void unstage_triangles(const HostStaging& staging, uint32_t count, TileFinal& f);
  // The same, each vertex mapped through `ids` on the way (the job's: f.global_ids). At 1B points a tile's
  // 250M triangles were copied, then read and written again to map them: 6 GB of host memory a tile.
  static void unstage_triangles(const HostStaging& staging, uint32_t count, std::span<const uint32_t> ids,
                                TileFinal& f);
  // Tiles of about `vertices` points to come (core/tiles' tile_staging_points, known before the plan): a tile of
  // made-up points that size run through `staging` and dropped, so that the device's buffers for tiles are
  // made while the host resolves and plans. At 1B points the first tile's device call took 1.1 s longer than
  // the next ones on one device, and 4 s longer on each of two devices allocating at once. The tile carries a
  // fifth as many segments as points, so that the constraint inserter's buffers (and the memory pool they grow)
  // are made too: at 1B + 250M on two H200s, without them the pools grew by 4.3 GB in the first tiles (75-90 ms
  // a device) and the tiles and merge took 4.67-4.72 s against 4.43-4.64. Its caller holds the device and its
  // copy queue.
  void warm_up_tiles(uint64_t vertices, HostStaging& staging) const;
  // Duplicate merging on the GPU for prepare(in, cdt.merger()); the same answer as the CPU's merge_points.
  PointMerger merger() const;

  // The paper's ablation switches (docs/gpu-constraints.md); defaults are the full method.
  ConstraintOptions constraint_options;
  // The Delaunay stage's settings, e.g. its start (`cdtgpu triangulate --initial-dt voronoi`); set before a run.
  DelaunayBuilder& delaunay() { return delaunay_; }
  const DelaunayBuilder& delaunay() const { return delaunay_; }
  // Threads of the CPU resolve stage (0: all).
  unsigned resolve_threads = 0;
  // Many runs in one process (cdtgpu batch): triangulate() keeps the triangulation's and the build's buffers for
  // the next run, as tiles do, instead of freeing them: 28 allocations and frees a run, 3.9 ms of a 20K-point
  // job's 17.7 on the H100 machine. Off (a single run): freed, the lower peak for the grid and contours after.
  bool keep_buffers = false;

  const Context& context() const { return ctx_; }
  // The scan and sort passes, for other GPU work of the same run (gpu/raster, gpu/contours).
  const Primitives& primitives() const { return prims_; }

  // Whether the caches keep a buffer under `key` (gpu/buffers.hpp BufferCache) for the next tile or run.
  bool keeps(const std::string& key) const { return cache_.holds(key) || kept_.holds(key); }
  // Frees what the caches keep between tiles and runs (a tiling given up for smaller tiles).
  void drop_kept() const {
    cache_.clear();
    kept_.clear();
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    shelf_->points.clear();
    shelf_->segments.clear();
    shelf_->sorted.clear();
  }

 private:
  // Upload and Delaunay build of all[ids[i]] (of all, when ids is empty), their stages added to `s`.
  // `keep`: the tiles' cache (DelaunayBuilder::build).
  GpuTriangulation delaunay_of(std::span<const Point3> all, std::span<const uint32_t> ids, GpuCdtStats& s,
                               BufferCache* keep = nullptr) const;
  // The build of uploaded points, its stages added to `s`.
  GpuTriangulation build(Buffer points, uint32_t n, GpuCdtStats& s, BufferCache* keep) const;
  // compute_tile's work. unresolved: TileJob::unresolved.
  uint32_t run_staged(TileUpload up, uint32_t n, std::span<const Edge> segments, const TileRect& rect,
                      HostStaging& staging, TileFinal& f, Buffer& sorted, GpuCdtStats& s,
                      bool unresolved = false) const;
  // A staging buffer's first n points on the device (the copy queue), in a buffer from the shelf.
  Buffer upload_points(uint64_t n, const HostStaging& staging) const;
  // One of the shelf's buffers at least `bytes` long (made when none is).
  Buffer from_shelf(std::vector<Buffer>& list, uint64_t bytes, const char* name, bool addressed) const;
  // Buffers of `bytes` added to the shelf's `list` until it holds two.
  void top_up_shelf(std::vector<Buffer>& list, uint64_t bytes, const char* name, bool addressed) const;
  // Stage 3: the constraints inserted.
  // recycle: the inserter's flags stay in the cache for the next tile or run. unresolved:
  // ConstraintOptions::unresolved, its splits into `split` (ConstrainedEdges::split). uploaded: the constraints
  // on the device already (ConstraintInserter::insert). sorted: ConstraintOptions::sorted.
  void constrain(GpuTriangulation& tri, std::span<const Edge> constraints, GpuCdtStats& s,
                 bool recycle = false, bool unresolved = false,
                 std::vector<std::array<uint32_t, 3>>* split = nullptr, const Buffer* uploaded = nullptr,
                 bool sorted = false) const;
  // The triangulation's buffers into kept_ (and the shared cache) for the next tile or run.
  void keep(GpuTriangulation& tri) const;
  // Stage 4: the triangles downloaded in canonical order into `storage`.
  Triangles download_sorted(GpuTriangulation& tri, GpuCdtStats& s, Triangles storage) const;

  const Context& ctx_;
  // One scratch cache for the stages, which run one after another: the Delaunay build's per-slot buffers are
  // the inserter's and the canonical sort's (gpu/buffers.hpp, shared keys), allocated once and kept.
  mutable BufferCache cache_;
  // Tiles and keep_buffers: the triangulation's own buffers and the build's numbering, kept from one tile or
  // run to the next.
  mutable BufferCache kept_;
  // The buffers tiles' copies hold beside another tile's compute (upload_tile, download_tile): points on their
  // way up (and segments), sorted triangles on their way down; two of each in steady state. Locked: the copies
  // run on other threads than the compute.
  struct Shelf {
    std::mutex mutex;
    std::vector<Buffer> points, segments, sorted;
  };
  std::unique_ptr<Shelf> shelf_ = std::make_unique<Shelf>();
  Primitives prims_;
  DelaunayBuilder delaunay_;
  ConstraintInserter inserter_;
  TriangleSorter sorter_;
  PointDeduper deduper_;
  TileFinalPasses finals_;
};

}  // namespace cdtgpu::gpu
