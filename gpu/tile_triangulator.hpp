// Tiles of core/tiles through one device or several: each tile's CDT is a whole GPU run (gpu/cdt_pipeline), one
// tile at a time on each device while other threads gather the next tiles and sort out the finished ones.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/tiles.hpp"
#include "gpu/cdt_pipeline.hpp"

namespace cdtgpu::gpu {

// Serialises its calls on `cdt`, which must outlive it; a DeviceError names the tile and its size. `sum`,
// when given (and outliving it): every call's stage times added up, by name, and the largest device memory
// peak.
TileTriangulator gpu_tile_triangulator(const GpuCdt& cdt, GpuCdtStats* sum = nullptr);
// Tiles spread over several devices (issue 29): each call takes a free device, waiting while all are busy, so
// run 2 x cdts.size() tiles in flight (TileOptions::tiles_in_flight). A tile's CDT is the same on every
// device, so the result does not depend on which device took which tile. A DeviceError names the device too.
TileTriangulator gpu_tile_triangulator(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum = nullptr);

// Both ways a tiled run uses the devices, sharing them: tiles through `finalize` (their final triangles and
// border found on the device, TileOptions::finalize), merges through `triangulate`.
struct GpuTiles {
  TileTriangulator triangulate;
  TileFinalizer finalize;
  // TileOptions::reserve: every slot's staging, on a thread a device; the first call for tiles of at least
  // `warm_up_from` points also warms each device up (GpuCdt::warm_up_tiles) unless a tile has begun. On devices
  // that warm up at all (warm_up_from not UINT64_MAX: hardware GPUs) the first call also holds each device's
  // clock up (gpu/clock_hold), after its warm-up, until the first tile: left idle through the host's prepare, an
  // H200's first tile ran at about half clock.
  std::function<void(uint64_t vertices)> reserve;
  std::function<size_t()> warm_ups;  // devices warmed up so far
  // TileOptions::tiles_done, for a run that tiles once: what only the tiles need (every device but the first,
  // every staging slot but the first) freed beside the merge. Later calls run on what is left, one at a time.
  std::function<void()> tiles_done;
  // Each device's clock held up until the next tile begins, as the first reserve holds it (at most 30 s): for a
  // caller that runs tiles again after host work of its own (the tiles bench between its runs). Nothing on a CPU
  // device.
  std::function<void()> hold_clocks;
};
// Tiles from which a warm-up pays on these devices: 100M points on one hardware GPU, 50M on each of several (their
// tiles shrink with the devices, the host's work before them does not). At 1B points (tiles of 134M) the resolve
// and plan take 6-14 s, the warm-up 1-2 s; at 256M (tiles of 64M) they take ~0.6 s, less than the warm-up, which
// the first tile would then wait for. At 1B + 250M on two H200s (tiles of 52M) the tiles and merge took 4.43-4.64
// s against 4.70-4.81 without it (session 67). Never on a CPU device (lavapipe), whose buffers cost nothing to
// make and whose compute is slow.
uint64_t warm_up_from(const std::vector<const GpuCdt*>& cdts);
// TileOptions::ramp for tiles of `tile_points` on these devices: 2 where the devices are warmed up for them
// (their buffers made for the largest tile, which thin first tiles would otherwise size) and the tiles are of
// 100M points or more (at 1B + 250M on two H200s, tiles of 52M not warmed up took 4.53-4.80 s with it against
// 4.42-4.48 without; session 67), else none. At 1B points
// on 2 x H200 a run took 3315 ms with it against 3585 without (the devices start on half a tile's copies
// and end on half a tile's bookkeeping); on one, 5388 against 5428.
unsigned tile_ramp(const std::vector<const GpuCdt*>& cdts, uint64_t tile_points);
// Tiles from which each device's buffers take their memory from a pool made with the first reserve, beside its
// staging (gpu/device_memory_pool.hpp; ~260 bytes a point): 8M points on hardware GPUs, where the driver's
// allocations and frees of every tile's buffers, several GB each, held the devices (and contended between two).
// Never on a CPU device, whose allocations cost nothing.
uint64_t device_pools_from(const std::vector<const GpuCdt*>& cdts);
// With the rules above; device_pools false: none (MPI ranks, which may share a device).
GpuTiles gpu_tiles(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum = nullptr, bool device_pools = true);
GpuTiles gpu_tiles(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum, uint64_t warm_up_from, uint64_t pools_from);

// The devices a tiled run spreads over, each with a context and a GpuCdt: borrowed (a device started already)
// or opened here, all at once (gpu/devices.hpp).
//
//   TileDevices d;
//   d.borrow(start.cdt());
//   d.open({1, 2, 3}, ContextOptions{});
//   TileTriangulator tri = gpu_tile_triangulator(d.cdts());   // 2 * d.cdts().size() tiles in flight
class TileDevices {
 public:
  TileDevices() = default;
  TileDevices(TileDevices&&) = default;
  TileDevices& operator=(TileDevices&&) = delete;
  // The opened devices closed at once, each on a thread of its own: after tiles of 1B points each took ~1.2 s
  // to free its buffers.
  ~TileDevices();
  void borrow(const GpuCdt& cdt);
  void open(const std::vector<size_t>& indices, const ContextOptions& options);
  const std::vector<const GpuCdt*>& cdts() const { return cdts_; }
  uint64_t max_tile_points() const;  // the smallest device's
  std::string names() const;         // "NAME (INDEX), ..."

 private:
  std::vector<std::unique_ptr<Context>> opened_;
  std::vector<std::unique_ptr<GpuCdt>> opened_cdts_;
  std::vector<const GpuCdt*> cdts_;
};

// The most points a tile of its own may hold on this device: the Delaunay build's slot limit and ~260 bytes
// of device memory a point (the measured peak, docs/performance.md), the storage buffer range (24 bytes a
// point in the constraint inserter's tables: 179M points on a 4 GiB range, 5.6M on lavapipe's 128 MiB), with
// a quarter to spare for the endpoints of the segments that cross into the tile.
uint64_t max_tile_points(const Context& ctx);
// The most any device takes (the Delaunay build's slot limit): an input beyond it is tiled on every device.
uint64_t max_tile_points_of_any_device();

}  // namespace cdtgpu::gpu
