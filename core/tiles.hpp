// The tiled constrained Delaunay triangulation: any input size through a device of bounded size, or on every
// CPU core, with exactly the triangles of the single run (../shared/notes/tiling.md, docs/tiles.md).
//
//   ResolvedInput in = resolve_constraints(prepared);      // crossings split on the whole, first
//   TileOptions opt{.max_tile_points = 500'000};
//   TileStats ts;
//   CdtResult r = triangulate_tiled(std::move(in), opt, cgal_tile_triangulator(), &ts);   // canonical mesh
//
// Steps (core/tiles.cpp reads as this list):
//   plan     k-d splits of the vertices by count (the median of the longer side's extent) until a tile holds
//   at
//            most max_tile_points; every tile is a closed rectangle, ±inf on the outside
//   tiles    each tile's CDT of its vertices plus every segment meeting its rectangle (segments whole, with
//            their endpoints: nothing is clipped, so a tile makes no vertex of its own); a triangle whose
//            closed circumdisk lies in the tile's open interior is *final*, a triangle of the whole CDT
//   merge    the CDT of what is left: the vertices not inside the final region, the segments among them, and
//            the final region's border edges as constraints; its triangles on the final side are dropped.
//            Tiled again while that shrinks it, else one call of the triangulator.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/cdt_cgal.hpp"
#include "core/model.hpp"
#include "core/resolve.hpp"

namespace cdtgpu {

// A tile's CDT: counter-clockwise triangles in any order, and optionally their neighbours (cdt_of_graph's
// layout: [3i + k] across the edge from vertex k to k + 1, UINT32_MAX on the hull); empty: worked out here.
struct TileMesh {
  Triangles triangles;
  std::vector<uint32_t> neighbours;
};

// The CDT of a planar straight-line graph: vertices sorted by (x, y) and unique, segments (a < b) sorted,
// meeting only at shared endpoints and holding no vertex inside. Called from several threads at once (a GPU
// triangulator serialises itself). `what` names the call for messages ("tile 3 of 16, level 1", "merge, level
// 1").
using TileTriangulator = std::function<TileMesh(const Points& vertices,
                                                const std::vector<Edge>& segments, std::string_view what)>;

// CGAL's constrained Delaunay triangulation (core/cdt_cgal.hpp, cdt_of_graph).
TileTriangulator cgal_tile_triangulator();

// A tile's closed rectangle; ±inf on the outside of the plan.
struct TileRect {
  double x0 = -std::numeric_limits<double>::infinity(), x1 = std::numeric_limits<double>::infinity();
  double y0 = -std::numeric_limits<double>::infinity(), y1 = std::numeric_limits<double>::infinity();
};

// The tiles' shape (core/tile_plan.hpp).
enum class TileShape { automatic, squares, slabs };

// A tile as a TileFinalizer takes it: its vertices are all[ids[i]] (ids sorted), its segments in those local
// indices (sorted).
struct TileJob {
  const Points& all;
  std::span<const uint32_t> ids;
  std::span<const Edge> segments;
  TileRect rect;
  std::string_view what;
  // The input is not resolved (TileOptions::unresolved): the finalizer splits a segment through a vertex
  // (TileFinal::split) and throws UnresolvedTile when two segments cross.
  bool unresolved = false;
};
// What a tile gives the merge, in local indices: its final triangles (closed circumdisk certainly inside the
// open rectangle; canonical order) and the final region's border within it (final triangles' edges not shared
// with another final triangle, directed with the final triangle on their left; any order).
struct TileFinal {
  Triangles triangles;
  std::vector<Edge> border;
  // The triangles are in the whole's ids already (ids[] applied; still canonical, ids being sorted): a GPU
  // finalizer maps them as it copies them out of its staging, one pass over them fewer.
  bool global_ids = false;
  // TileJob::unresolved: segments (a, b) the tile split at a vertex v exactly inside them, as (a, b, v) in local
  // ids (a piece of an earlier split may be split again). Every vertex of the tile inside one of its segments
  // is such a v.
  std::vector<std::array<uint32_t, 3>> split;
};
// A triangulator that finds a tile's final triangles and border itself (the GPU's, next to its neighbours),
// instead of handing back the whole tile for the host to test. It may take fewer triangles as final than
// circumdisk_inside (a stricter test only makes the merge larger), never more.
using TileFinalizer = std::function<TileFinal(const TileJob&)>;

struct TileOptions {
  uint64_t max_tile_points =
      0;  // at most this many of a tile's own vertices; below 3 or >= the input: no tiles
  // A merge tiled again only while it holds at most this share of its level's vertices (else one call).
  double retile_share = 0.6;
  // Tiles worked on at once, a sliding window (0: as many as the cores take). A device's tiles are large: two at
  // once (one on the device, the next gathered meanwhile) bound host memory by the tile size.
  unsigned tiles_in_flight = 0;
  // Threads beyond the cores for the tiles, which tiles run by other processes hold while they wait
  // (core/tile_workers.hpp): so many more tiles at once, with the cores still busy with the others.
  unsigned waiting_threads = 0;
  // core/tile_plan.hpp; `automatic` is squares without a finalizer (the CPU's tiles); tests force slabs.
  TileShape shape = TileShape::automatic;
  // Slabs only: the first and the last slab cut into this many thinner ones (core/tile_plan.hpp), so that the
  // devices start and end on smaller tiles. cdtgpu triangulate takes 2 where its devices are warmed up for the
  // largest tile (gpu::tile_ramp), else none: a device's buffers are sized by its first tile, and a thin one
  // would make them all regrow at the next (`bench --table tiles --tile-ramps` tries others; docs/tiles.md).
  unsigned ramp = 0;
  // The input is not resolved, and the finalizer checks each first-level tile for what the resolve would split
  // (TileJob::unresolved; the GPU's constraint insertion meets every such case). A tile with two segments that
  // cross throws UnresolvedTile. A segment through vertices is split at them in each tile that has them
  // (TileFinal::split), and the merge takes the segments split at every such vertex (core/split_at_vertices.hpp):
  // the resolve's result, for an input without crossings. The first level's tiles see every case: a segment goes
  // to every tile it meets, so two crossing segments both go to a tile holding their crossing point, and a
  // segment through a vertex to the tile that owns the vertex. Needs `finalize`.
  bool unresolved = false;
  // Tiles (of every level) through this instead of the triangulator plus the host's final test; the merges
  // still take the triangulator. Empty: the host's test.
  TileFinalizer finalize;
  // Told a first-level tile's vertex count (tile_staging_points) before the plan, and again after it if a tile
  // is larger: a GPU finalizer allocates its pinned staging meanwhile.
  std::function<void(uint64_t vertices)> reserve;
  // Called once the first level's tiles are done, before their merge: a GPU run frees the devices and staging
  // that only the tiles needed (GpuTiles::tiles_done), beside the merge. Later calls still work, on what is left.
  std::function<void()> tiles_done;
  // The first level's canonical order left in the tiles' runs (tiled_cdt_runs, CdtResult::in_runs) when its
  // tiles are slabs: for a caller that only writes the mesh, which then reads them in place (RunMerge::in_place).
  bool in_runs = false;
};

// CGAL's CDT of the tile (`triangulate`) and the host's final test: what a tile without a finalizer gets, as a
// finalizer (for tiles run by another process, core/tile_workers.hpp). Its results are in the tile's ids.
TileFinalizer host_finalizer(TileTriangulator triangulate);

// A finalizer's throw when a tile of an unresolved input (TileOptions::unresolved) has segments that cross (or
// more vertices on its segments than the GPU's passes split: gpu/constraints.cpp).
struct UnresolvedTile : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct TileStats {
  uint64_t tiles = 0;                 // tiles of every level
  uint64_t levels = 0;                // 1: tiles and one merge; 2: the merge was tiled once more; ...
  uint64_t final_triangles = 0;       // final in the first level's tiles (later levels' may be dropped again)
  uint64_t merge_vertices = 0;        // the last merge, the one triangulated in one call
  uint64_t merge_segments = 0;        // its constraints (segments and final-region border edges)
  uint64_t merge_triangles = 0;       // its triangles kept
  double tiles_ms = 0, merge_ms = 0;  // wall time: tiles and their bookkeeping, the last merge's call
  // Parts of tiles_ms, every level: the k-d plan and the segments' tiles (wall), the tiles' triangulator
  // calls and the rest of their work (summed over threads), building the merge input and keeping its
  // triangles (wall).
  double plan_ms = 0, tile_cdt_thread_ms = 0, tile_other_thread_ms = 0, merge_input_ms = 0, keep_ms = 0;
  double tile_gather_thread_ms = 0, tile_final_thread_ms = 0;  // of tile_other: the input, the final test + border
  double order_ms = 0;  // the tiles' and the merge's sorted runs merged into canonical order (wall)
  // TileOptions::unresolved: splits at vertices, counted as ResolvedInput::split_at_vertices counts them.
  uint64_t split_at_vertices = 0;
};

// The triangles of CDT(vertices, segments) (the graph as TileTriangulator takes it), tiled as `options` say,
// in canonical order (core/canonical.hpp): each starts at its smallest index, the list sorted.
Triangles tiled_cdt(const Points& vertices, const std::vector<Edge>& segments,
                                const TileOptions& options, const TileTriangulator& triangulate,
                                TileStats* stats = nullptr);

// tiled_cdt's triangles, left in the tiles' runs where options.in_runs says so.
OrderedRuns tiled_cdt_runs(const Points& vertices, const std::vector<Edge>& segments, const TileOptions& options,
                           const TileTriangulator& triangulate, TileStats* stats = nullptr);

// The whole mesh of a resolved input, canonical: the bytes of triangulate_cgal(prepared) for the prepared
// input `in` was resolved from. `in` is moved from only once the triangles are made: when the triangulator
// throws, it is left whole (the CLI's CPU fallback tiles it again). options.in_runs: in CdtResult::in_runs.
CdtResult triangulate_tiled(ResolvedInput&& in, const TileOptions& options,
                            const TileTriangulator& triangulate, TileStats* stats = nullptr);

// `--tiles-out`: a canonical mesh cut into pieces, one file each. Tiles planned over its vertices as for
// triangulation (at most tile_points of their own); a triangle belongs to the tile holding its smallest vertex
// (its first, in canonical order), so every triangle is in exactly one piece; a piece holds its triangles'
// vertices (a vertex shared by pieces is in each) and its own vertices that no triangle uses. Each piece is
// canonical; the union of the pieces is the mesh.
struct MeshPiece {
  Mesh mesh;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // its vertices' extent
};
std::vector<MeshPiece> split_mesh(const Mesh& mesh, uint64_t tile_points);

// Whether the closed circumdisk of abc lies in the open rectangle (x0, x1) x (y0, y1) (±inf allowed): the
// tiles' test of a final triangle. True only when it certainly does; near-ties and flat triangles answer
// false.
bool circumdisk_inside(const Point3& a, const Point3& b, const Point3& c, double x0, double x1, double y0,
                       double y1);

// The tile size `--max-tile-points` auto picks for the CPU: 0 (no tiles) below min_points or on one core,
// else vertices / (4 x cores), so that every core has a few tiles (docs/tiles.md has the measurements).
uint64_t auto_cpu_tile_points(uint64_t vertices, unsigned cores);
// The tile size `--max-tile-points` auto picks for GPU tiles on `devices` devices that take at most device_max
// points each: on one device vertices / 4, so that it has a few tiles (two in flight), as `bench --table tiles`
// has measured since session 45; on several, vertices / (12 x devices), but at least 2^25 and vertices / 64 (at
// most 64 slabs) and at most vertices / (4 x devices); at most device_max. Several devices' memory and pinned
// staging are made and freed by the driver one device after another (~25 ms and ~250 ms a GB; docs/tiles.md,
// session 63), and what the tiles hold when they are done is freed after them: at 1B + 250M on two H200s, 32
// slabs of 39M ended the whole run in 17.8-18.1 s against 20.4-20.9 s for 12 of 134M (the tiles and merge the
// same, 5.3 s; the pools 14.6 GB a device against 46-50), 16 of 78M 19.2-19.5 s (session 64). Each tile costs
// the device ~20 ms besides its GPU work (host work between its ~35 submits, their latency), and small tiles'
// rounds more GPU time: 24 slabs of 52M ended the run in 13.7-14.0 s against 14.1-15.2 for 32 of 39M, the tiles
// and merge 4.34-4.41 s against 4.75-4.93 (session 66). On one device, 32 slabs gave 21.9 s against 22.0 (the
// tiles 8.7 s against 7.4; session 64).
uint64_t auto_gpu_tile_points(uint64_t vertices, uint64_t device_max, size_t devices);
// The points a tile's staging (TileOptions::reserve) is sized for before the plan: tiles of about n / ceil(n /
// max) points (the plan's cells are no larger, but for rounding), with room for segments' far endpoints.
uint64_t tile_staging_points(uint64_t n, uint64_t max_tile_points);

}  // namespace cdtgpu
