#include "gpu/cdt_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <execution>
#include <future>
#include <memory>
#include <utility>

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "core/parallel.hpp"
#include "core/resolve.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"
#include "gpu/triangulation.hpp"

namespace cdtgpu::gpu {
namespace {

using Clock = std::chrono::steady_clock;

void add_gpu(GpuCdtStats& s, const std::string& prefix, const std::vector<std::pair<std::string, double>>& stages) {
  for (const auto& [name, ms] : stages) {
    s.gpu_ms.emplace_back(prefix + name, ms);
    s.gpu_total_ms += ms;
  }
}

// Host wall clock of a stage since t0, into the stats and the -v log.
void record_stage(GpuCdtStats& s, const char* name, Clock::time_point t0) {
  s.wall_ms.emplace_back(name, ms_since(t0));
  spdlog::debug("gpu backend: {}: {:.1f} ms", name, s.wall_ms.back().second);
}

// A buffer the tiles' copies hold, made with room: tiles come in sizes a few % apart.
uint64_t shelf_room(uint64_t bytes) { return bytes + bytes / 16; }

// The host array for the triangles of n vertices (at most 2n), its pages touched on other cores while the GPU
// works: fresh memory costs a page fault per 4 KiB, ~15 ms for 2.5M points, which the download would wait for.
std::future<Triangles> triangle_storage(size_t n) {
  return std::async(std::launch::async, [n] {
    Triangles v;
    resize_touched(v, 2 * n);
    return v;
  });
}

}  // namespace

GpuCdt::GpuCdt(const Context& ctx)
    : ctx_(ctx),
      prims_(ctx),
      delaunay_(ctx),
      inserter_(ctx, prims_),
      sorter_(ctx, prims_),
      deduper_(ctx, prims_),
      finals_(ctx) {
  delaunay_.cache = &cache_;
  inserter_.cache = &cache_;
  sorter_.cache = &cache_;
}

PointMerger GpuCdt::merger() const {
  return [this](std::span<const double> xy) { return merge_points(deduper_, xy); };
}

CdtResult GpuCdt::triangulate(const PreparedInput& prepared, GpuCdtStats* stats) const {
  // Refused before the resolve starts, not after it (8 s at 1B points): the resolve only adds vertices.
  require_storage_range(ctx_, uint64_t(prepared.vertices.size()) * 16, "points");
  ResolveProgress progress;
  return triangulate(prepared, std::async(std::launch::async, [&] {
                       return resolve_constraints(prepared, progress, resolve_threads);
                     }),
                     stats, &progress);
}

namespace {

// x, y of all[ids[i]] (of all, when ids is empty) as doubles into `mapped`, on all cores: 40 MB took 12-19 ms on one.
void write_points(std::span<const Point3> all, std::span<const uint32_t> ids, void* mapped) {
  double* xy = static_cast<double*>(mapped);
  const uint32_t n = static_cast<uint32_t>(ids.empty() ? all.size() : ids.size());
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, n, 1 << 16), [&](const tbb::blocked_range<uint32_t>& r) {
    for (uint32_t i = r.begin(); i < r.end(); ++i) {
      const Point3& p = all[ids.empty() ? i : ids[i]];
      xy[2 * i] = p.x, xy[2 * i + 1] = p.y;
    }
  });
}

}  // namespace

GpuTriangulation GpuCdt::delaunay_of(std::span<const Point3> all, std::span<const uint32_t> ids,
                                     GpuCdtStats& s, BufferCache* keep) const {
  auto t = Clock::now();
  const uint32_t n = static_cast<uint32_t>(ids.empty() ? all.size() : ids.size());
  Buffer points = keep ? keep->take(ctx_, "points", uint64_t(n) * 16) : create_buffer(ctx_, uint64_t(n) * 16, "points");
  upload_with(ctx_, points, uint64_t(n) * 16, [&](void* mapped) { write_points(all, ids, mapped); });
  record_stage(s, "upload", t);
  return build(std::move(points), n, s, keep);
}

GpuTriangulation GpuCdt::build(Buffer points, uint32_t n, GpuCdtStats& s, BufferCache* keep) const {
  const auto t = Clock::now();
  GpuTriangulation tri = delaunay_.build(std::move(points), n, &s.delaunay, keep);
  record_stage(s, "delaunay", t);
  add_gpu(s, "dt ", s.delaunay.stage_ms);
  s.peak_device_bytes = std::max(s.peak_device_bytes, s.delaunay.peak_device_bytes);
  return tri;
}

CdtResult GpuCdt::triangulate(const PreparedInput& prepared, std::future<ResolvedInput> resolving,
                              GpuCdtStats* stats, const ResolveProgress* progress) const {
  GpuCdtStats local;
  GpuCdtStats& s = stats ? *stats : local;
  s = GpuCdtStats{};
  const auto t_all = Clock::now();

  // Room for the Steiner vertices of a few crossings too: regrowing it after the download is 60 MB copied and
  // faulted on one core at 2M points (37 ms more in the download with a boundary crossing the contours).
  const size_t room = prepared.vertices.size() + prepared.vertices.size() / 256 + 4096;
  std::future<Triangles> triangles = triangle_storage(room);

  // 1. CPU, on other threads (`resolving`): constraints that pass through vertices are split there, crossings
  //    get Steiner vertices, so that the GPU sees a planar straight-line graph on canonical vertices.
  // 2. GPU, meanwhile: the Delaunay triangulation of the prepared vertices, left on the device. They are the
  //    resolved vertices unless constraints cross somewhere; then the triangulation is built again from those.
  //    Of the resolved vertices where the resolve is done already (it often is when the device was slower to
  //    start) or has found crossings (a second build costs more than the wait).
  auto wait = [&] {
    const auto t = Clock::now();
    ResolvedInput r = resolving.get();
    record_stage(s, "resolve wait", t);
    return r;
  };
  const bool resolved = resolving.wait_for(std::chrono::seconds(0)) == std::future_status::ready ||
                        (progress && progress->crossings.load() == 1);
  ResolvedInput in = resolved ? wait() : ResolvedInput{};
  BufferCache* kept = keep_buffers ? &kept_ : nullptr;
  GpuTriangulation tri = delaunay_of(resolved ? in.vertices : prepared.vertices, {}, s, kept);
  if (!resolved) {
    in = wait();
    if (in.vertices.size() != prepared.vertices.size()) {  // resolve only ever adds vertices
      if (kept) keep(tri);
      tri = GpuTriangulation();
      tri = delaunay_of(in.vertices, {}, s, kept);
      s.delaunay_built_twice = true;
    }
  }
  if (in.vertices.size() > room) triangles = triangle_storage(in.vertices.size());
  s.split_at_vertices = in.split_at_vertices;
  CdtResult result;
  result.steiner_points = in.steiner_points;
  result.mesh.vertices = std::move(in.vertices);

  constrain(tri, in.constraints, s, keep_buffers);
  result.mesh.triangles = download_sorted(tri, s, triangles.get());
  if (kept) keep(tri);
  s.wall_total_ms = ms_since(t_all);
  return result;
}

void GpuCdt::keep(GpuTriangulation& tri) const {
  kept_.give("points", std::move(tri.points));
  kept_.give("tri_verts", std::move(tri.verts));
  kept_.give("tri_nbrs", std::move(tri.nbrs));
  if (tri.vertex_slots.buffer) cache_.give(kPoints4[0], std::move(tri.vertex_slots));  // the build's loc
}

void GpuCdt::constrain(GpuTriangulation& tri, std::span<const Edge> constraints, GpuCdtStats& s,
                       bool recycle, bool unresolved, std::vector<std::array<uint32_t, 3>>* split,
                       const Buffer* uploaded, bool sorted) const {
  // 3. GPU: every constraint becomes an edge by flips, then the constrained Delaunay property by flips.
  //    No slots: fewer than 3 vertices or all collinear, so no triangles for the constraints to change; no
  //    constraints: the Delaunay triangulation is the answer.
  auto t = Clock::now();
  if (tri.num_slots > 0 && !constraints.empty()) {
    ConstraintOptions options = constraint_options;
    options.unresolved = unresolved;
    options.sorted = sorted;
    ConstrainedEdges edges = inserter_.insert(tri, constraints, &s.constraints, options, uploaded);
    if (split) *split = std::move(edges.split);
    if (recycle) inserter_.recycle(std::move(edges));  // its flags, for the next tile or run
    add_gpu(s, "cdt ", s.constraints.stage_ms);
    s.peak_device_bytes = std::max(s.peak_device_bytes, s.constraints.peak_device_bytes);
  }
  record_stage(s, "constraints", t);
}

Triangles GpuCdt::download_sorted(GpuTriangulation& tri, GpuCdtStats& s,
                                              Triangles storage) const {
  // 4. The finite triangles, sorted into canonical order on the GPU, then downloaded.
  auto t = Clock::now();
  double sort_ms = 0;
  Triangles triangles = sorter_.download(tri, &sort_ms, std::move(storage));
  // During the sort: the triangulation and every scratch buffer the stages left in the cache (the sort takes
  // its own from there too).
  const uint64_t sorting = tri.points.size + tri.verts.size + tri.nbrs.size + tri.vertex_slots.size + cache_.bytes();
  s.peak_device_bytes = std::max(s.peak_device_bytes, sorting);
  add_gpu(s, "", {{"canonical order", sort_ms}});
  record_stage(s, "download", t);
  return triangles;
}

Triangles GpuCdt::triangulate_graph(const Points& vertices, const std::vector<Edge>& segments,
                                                GpuCdtStats* stats) const {
  GpuCdtStats local;
  GpuCdtStats& s = stats ? *stats : local;
  s = GpuCdtStats{};
  const auto t_all = Clock::now();
  std::future<Triangles> storage = triangle_storage(vertices.size());
  // With the tiles' buffers, given back after: a merge after tiles of 125M points took the inserter's flags and
  // the build's numbering from the caches and freed them (1.6 GB, 38 ms on the run's serial path).
  GpuTriangulation tri = delaunay_of(vertices, {}, s, &kept_);
  constrain(tri, segments, s, true);
  Triangles triangles = download_sorted(tri, s, storage.get());
  keep(tri);
  s.wall_total_ms = ms_since(t_all);
  return triangles;
}

TileFinal GpuCdt::finalize_tile(const TileJob& job, GpuCdtStats* stats) const {
  GpuCdtStats local;
  GpuCdtStats& s = stats ? *stats : local;
  s = GpuCdtStats{};
  HostStaging staging;  // the parts below, with a staging buffer of the call's own
  staging.fit(ctx_, staging_bytes(job.ids.size()));
  const bool segments_sorted = stage_points(job, staging);
  TileFinal f;
  Buffer sorted;
  TileUpload up = upload_tile(job, staging, s);
  up.segments_sorted = segments_sorted;
  const uint32_t count = compute_tile(job, std::move(up), staging, f, sorted, s);
  download_tile(std::move(sorted), count, staging, s);
  unstage_triangles(staging, count, f);
  return f;
}

uint64_t GpuCdt::staging_bytes(uint64_t vertices) {
  return std::max<uint64_t>(16, 2 * sizeof(Triangle)) * vertices;  // the points, at most 2n triangles
}

namespace {
// Where a tile's segments lie in its staging buffer, if they fit there: behind its points.
bool segments_staged(uint64_t n, uint64_t m) { return m > 0 && m <= n; }
uint64_t segments_offset(uint64_t n) { return n * 16; }
}  // namespace

bool GpuCdt::stage_points(const TileJob& job, HostStaging& staging) {
  const uint64_t n = job.ids.size(), m = job.segments.size();
  if (!segments_staged(n, m)) {
    write_points(job.all, job.ids, staging.mapped);
    return false;
  }
  // Beside the points: the inserter's check, which an uploaded list skips, then the copy, and whether the list
  // is sorted (the inserter's split looks its pieces up: read there, on one core, it held the device 20-40 ms).
  Edge* to = reinterpret_cast<Edge*>(static_cast<char*>(staging.mapped) + segments_offset(n));
  bool sorted = false;
  tbb::parallel_invoke([&] { write_points(job.all, job.ids, staging.mapped); },
                       [&] {
                         check_constraint_ids(job.segments, n);
                         copy_on_all_cores(job.segments.data(), m, to);
                       },
                       [&] { sorted = std::is_sorted(std::execution::par, job.segments.begin(), job.segments.end()); });
  return sorted;
}

Buffer GpuCdt::from_shelf(std::vector<Buffer>& list, uint64_t bytes, const char* name, bool addressed) const {
  Buffer b;
  {
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    auto fits = std::find_if(list.begin(), list.end(), [&](const Buffer& x) { return x.size >= bytes; });
    if (fits == list.end() && !list.empty()) fits = list.begin();  // too small: dropped below, a lower peak
    if (fits != list.end()) {
      b = std::move(*fits);
      list.erase(fits);
    }
  }
  if (b.size >= bytes && b.buffer) return b;
  b = Buffer();
  return addressed ? create_addressed_buffer(ctx_, shelf_room(bytes), name)
                   : create_buffer(ctx_, shelf_room(bytes), name);
}

void GpuCdt::top_up_shelf(std::vector<Buffer>& list, uint64_t bytes, const char* name, bool addressed) const {
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(shelf_->mutex);
      if (list.size() >= 2) return;
    }
    Buffer b = addressed ? create_addressed_buffer(ctx_, bytes, name) : create_buffer(ctx_, bytes, name);
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    list.push_back(std::move(b));
  }
}

Buffer GpuCdt::upload_points(uint64_t n, const HostStaging& staging) const {
  Buffer points = from_shelf(shelf_->points, n * 16, "points", false);
  copy_from_staging(ctx_, staging, points, n * 16, Queue::copy);
  return points;
}

GpuCdt::TileUpload GpuCdt::upload_tile(const TileJob& job, const HostStaging& staging, GpuCdtStats& s) const {
  const auto t = Clock::now();
  const uint64_t n = job.ids.size(), m = job.segments.size();
  TileUpload up{upload_points(n, staging), {}};
  if (segments_staged(n, m)) {
    up.segments = from_shelf(shelf_->segments, m * 8, "cdt constraints", false);
    copy_from_staging(ctx_, staging, up.segments, m * 8, Queue::copy, segments_offset(n));
  }
  record_stage(s, "upload", t);
  return up;
}

uint32_t GpuCdt::compute_tile(const TileJob& job, TileUpload up, HostStaging& staging, TileFinal& f, Buffer& sorted,
                              GpuCdtStats& s) const {
  return run_staged(std::move(up), uint32_t(job.ids.size()), job.segments, job.rect, staging, f, sorted, s,
                    job.unresolved);
}

void GpuCdt::download_tile(Buffer sorted, uint32_t count, const HostStaging& staging, GpuCdtStats& s) const {
  const auto t = Clock::now();
  copy_to_staging(ctx_, sorted, staging, uint64_t(count) * sizeof(Triangle), Queue::copy);
  record_stage(s, "download", t);
  std::lock_guard<std::mutex> lock(shelf_->mutex);
  shelf_->sorted.push_back(std::move(sorted));
}

uint32_t GpuCdt::run_staged(TileUpload up, uint32_t n, std::span<const Edge> segments, const TileRect& rect,
                            HostStaging& staging, TileFinal& f, Buffer& sorted, GpuCdtStats& s,
                            bool unresolved) const {
  const auto t_all = Clock::now();
  // The device's other copies of this call (the build's uploads, the border) go through `staging` as well, once
  // the points have left it: a pinned buffer per tile in flight and none more for the context.
  const StagingLent lent(ctx_, staging);
  cache_.grow_by = kept_.grow_by = 0.125;  // this GpuCdt takes tiles: sizes a few % apart
  cache_.first_room = kept_.first_room = 1.0 / 16;
  {
    // The build's triangle buffer: one whose download has ended, while the last tile's may still be coming down.
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    if (!shelf_->sorted.empty()) {
      kept_.give("tri_nbrs", std::move(shelf_->sorted.back()));
      shelf_->sorted.pop_back();
    }
  }
  GpuTriangulation tri = build(std::move(up.points), n, s, &kept_);
  constrain(tri, segments, s, /*recycle=*/true, unresolved, &f.split, up.segments.buffer ? &up.segments : nullptr,
            up.segments.buffer && up.segments_sorted);
  if (up.segments.buffer) {
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    shelf_->segments.push_back(std::move(up.segments));
  }
  auto t = Clock::now();
  double ms = 0;
  f.border = finals_.mark(tri, rect, cache_, &ms);
  add_gpu(s, "", {{"tile final", ms}});
  record_stage(s, "tile final", t);
  t = Clock::now();
  const uint32_t count = sorter_.sort(tri, &ms);
  add_gpu(s, "", {{"canonical order", ms}});
  record_stage(s, "canonical order", t);
  // The sorted triangles stay in tri.nbrs for download_tile; the points go back to the shelf for an upload.
  sorted = std::move(tri.nbrs);
  {
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    shelf_->points.push_back(std::move(tri.points));
  }
  keep(tri);
  s.wall_total_ms += ms_since(t_all);
  return count;
}

void GpuCdt::warm_up_tiles(uint64_t vertices, HostStaging& staging) const {
  if (vertices < 3 || vertices > UINT32_MAX) return;
  const uint32_t n = uint32_t(vertices);
  staging.fit(ctx_, staging_bytes(n));
  // A jittered grid, sheared so that x grows along the list: already sorted and unique, no degeneracy.
  double* xy = static_cast<double*>(staging.mapped);
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(n))));
  for (uint32_t i = 0; i < n; ++i) {
    uint64_t h = (uint64_t(i) + 1) * 0x9E3779B97F4A7C15ull;
    h = (h ^ (h >> 31)) * 0xBF58476D1CE4E5B9ull;
    const uint32_t c = i / side, r = i % side;
    xy[2 * i] = c + 0.5 * r / side;
    xy[2 * i + 1] = r + 0.5 * double(h >> 11) * 0x1p-53;
  }
  // A fifth as many segments, each between two neighbours of a column (none crosses another or meets a third
  // point), so that the constraint inserter's buffers are made too: real tiles carry about as many.
  std::vector<Edge> segments;
  segments.reserve(n / 5 + 1);
  for (uint32_t i = 0; i + 1 < n; i += 5)
    if ((i + 1) % side != 0) segments.push_back({i, i + 1});
  GpuCdtStats s;
  TileFinal f;
  Buffer sorted;
  run_staged(TileUpload{upload_points(n, staging), {}}, n, segments, TileRect{}, staging, f, sorted, s);
  // Two of each buffer the copies hold, made now too: while a tile computes, the next one's points go up and the
  // last one's triangles come down.
  const uint64_t sorted_bytes = sorted.size;
  {
    std::lock_guard<std::mutex> lock(shelf_->mutex);
    shelf_->sorted.push_back(std::move(sorted));
  }
  top_up_shelf(shelf_->points, shelf_room(uint64_t(n) * 16), "points", false);
  top_up_shelf(shelf_->sorted, sorted_bytes, "tri_nbrs", true);
}

namespace {
// The border as the device appended it, sorted beside the copy: sorted while the device was held (one core),
// it took most of a tile's final step, 110-130 ms a 20M-point tile whose border holds 0.9M edges (the 100M
// LAS points + 25M contour vertices).
template <class Copy>
void unstage_with_border(TileFinal& f, Copy&& copy) {
  tbb::parallel_invoke(copy, [&] { tbb::parallel_sort(f.border.begin(), f.border.end()); });
}
}  // namespace

void GpuCdt::unstage_triangles(const HostStaging& staging, uint32_t count, TileFinal& f) {
  resize_unwritten(f.triangles, count);
  unstage_with_border(
      f, [&] { copy_on_all_cores(static_cast<const Triangle*>(staging.mapped), count, f.triangles.data()); });
}

void GpuCdt::unstage_triangles(const HostStaging& staging, uint32_t count, std::span<const uint32_t> ids,
                               TileFinal& f) {
  resize_unwritten(f.triangles, count);
  const Triangle* from = static_cast<const Triangle*>(staging.mapped);
  Triangle* to = f.triangles.data();
  unstage_with_border(f, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        to[i] = {ids[from[i][0]], ids[from[i][1]], ids[from[i][2]]};
    });
  });
  f.global_ids = true;
}

}  // namespace cdtgpu::gpu
