// Shared between C++ (gpu/*.cpp) and GLSL (shaders/*.comp): workgroup sizes, element structs and push-constant
// blocks. One source of truth, so host and shader layouts cannot drift. Only 32-bit scalar members (and, in
// SegmentRecord, doubles at 8-byte offsets), so std430 (buffers) and the push-constant layout equal the C++
// layout.
#ifndef CDTGPU_SHADERS_LAYOUT_H
#define CDTGPU_SHADERS_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
namespace cdtgpu::gpu::layout {
using uint = uint32_t;
#endif

// Exclusive scan: a workgroup scans SCAN_BLOCK consecutive elements (SCAN_ITEMS per invocation).
#define SCAN_WG 256
#define SCAN_ITEMS 8
#define SCAN_BLOCK (SCAN_WG * SCAN_ITEMS)

struct ScanPush {
  uint n;           // elements to scan
  uint write_sums;  // 1: write each block's total to block_sums[block]
  uint binarize;    // 1: scan (in[i] != 0) instead of in[i] (compaction flags)
};

struct ScanAddPush {
  uint n;  // elements; block b gets offsets[b] added
};

#define COMPACT_WG 256
struct CompactPush {
  uint n;
};

// Radix sort: 8 bits per pass. Each subgroup owns a tile of (subgroup size * RADIX_ITEMS) consecutive keys, so
// the histogram has RADIX_BINS counts per tile, stored digit-major: hist[digit * num_tiles + tile].
#define RADIX_WG 64
#define RADIX_ITEMS 16
#define RADIX_BINS 256
#define RADIX_MIN_SUBGROUP 8
#define RADIX_MAX_SUBGROUPS (RADIX_WG / RADIX_MIN_SUBGROUP)

struct RadixPush {
  uint n;          // keys
  uint shift;      // bit position of this pass's digit (0, 8, ..., 56)
  uint wide;       // 1: keys are 64-bit (two uint words each)
  uint num_tiles;  // ceil(n / tile size)
  uint tile_size;  // subgroup size * RADIX_ITEMS
};


// The triangulation on the GPU (gpu/triangulation.hpp): a closed triangulation of the sphere, finite triangles
// plus one infinite triangle per convex-hull edge whose third vertex is the symbolic INF_VERTEX.
// verts[3t+k]: vertex k of slot t, counter-clockwise. nbrs[3t+k]: the triangle across the edge opposite
// vertex k, as NBR(tri, k') with k' the index of the same edge in that triangle.
#define INF_VERTEX 0xFFFFFFFFu
#define NO_TRI 0xFFFFFFFFu
#define NBR(tri, k) (((tri) << 2) | (k))
#define NBR_TRI(code) ((code) >> 2)
#define NBR_EDGE(code) ((code) & 3u)

// Canonical output order (gpu/canonical.cpp): buckets by smallest vertex, or one sort key per slot.
#define CANONICAL_WG 256
#define CANONICAL_BUCKET_MAX 64u  // larger buckets: the radix sort instead
struct CanonicalKeysPush {
  uint num_slots;
  uint num_points;  // infinite slots get vertex num_points first, after every finite triangle
  uint shift;       // bits of each vertex field in the key: the bit width of num_points (1..31)
};


// DEM grid of a TIN (gpu/raster.cpp). Band by band: raster_spans gives each triangle its rows and columns of
// cell centres inside the band, a scan lays out one work item per (triangle, row), raster_claim keeps in
// owner[cell] the smallest triangle whose closed area holds the centre (atomicMin: the CPU's "first triangle
// in mesh order") where the orientation filters decide, and queues the (triangle, row, column) they cannot
// decide for raster_exact; raster_values writes the winner's interpolated z (or NODATA).
// Grid numbers in the params buffer (doubles, indices below): centre x of column c is (kx0 + c) * cell, centre
// y of grid row r is (ky_top - r) * cell, integers held exactly in doubles (|k| < 2^53).
#define RASTER_WG 64
#define RASTER_CELL 0
#define RASTER_KX0 1
#define RASTER_KY_TOP 2
#define RASTER_NODATA 3
#define RASTER_PARAMS 4
#define RASTER_NO_TRI 0xFFFFFFFFu
struct RasterPush {
  uint num_tris;
  uint ncols;
  uint row0;   // first grid row of the band
  uint rows;   // rows in the band
  uint items;      // (triangle, row) work items of the band (raster_claim)
  uint queue_cap;  // entries the exact queue holds (raster_claim counts past it; the host then grows it)
};

// Contour lines (gpu/contours.cpp): contour_count gives each triangle the levels it crosses (first index and
// count; levels[] ascending), a scan gives offsets, contour_write writes one SegmentRecord per (triangle,
// level) in triangle order. `edges`: bits 0-1 the triangle edge (k -> k+1) the segment starts on, bits 2-3
// the one it ends on (already swapped for a clockwise triangle).
#define CONTOUR_WG 64
struct ContourPush {
  uint tri0;      // first triangle of this chunk
  uint num_tris;  // triangles in the chunk
  uint num_levels;
};
// 48 bytes: the doubles sit at 8-byte offsets, so std430 and C++ agree here too.
struct SegmentRecord {
  uint tri;
  uint level;  // index into levels[]
  uint edges;
  uint pad;
  double px, py, qx, qy;  // from point, to point
};

// A tile's final triangles (gpu/tile_final.cpp, core/tiles.hpp): tile_final flags the slots whose closed
// circumdisk certainly lies in the open rectangle, tile_border lists the final region's border and unlists the
// other slots for the canonical sort. Doubles first, so std430 and C++ agree.
#define TILE_WG 256
#define TILE_SIDE_X0 1u  // the sides that are finite (the plan's outer sides are at infinity)
#define TILE_SIDE_X1 2u
#define TILE_SIDE_Y0 4u
#define TILE_SIDE_Y1 8u
struct TileFinalPush {
  double x0, x1, y0, y1;
  uint num_slots;
  uint sides;     // TILE_SIDE_* bits
  uint capacity;  // border edges the buffer holds (tile_border)
  uint pad;
};

// A spin that keeps a waiting device's clock up (gpu/clock_hold): one workgroup steps a chain of numbers.
#define CLOCK_HOLD_WG 64
#define CLOCK_HOLD_MAX (65535u * 64u)  // steps a spin: see clock_hold.comp
struct ClockHoldPush {
  uint steps;
  uint seed;
};

#ifdef __cplusplus
}  // namespace cdtgpu::gpu::layout
#endif

#endif
