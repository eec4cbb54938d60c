#include "gpu/tile_triangulator.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <mutex>

#include "gpu/check.hpp"
#include "shaders/layout_dt.h"

namespace cdtgpu::gpu {

namespace {

void add(std::vector<std::pair<std::string, double>>& sum,
         const std::vector<std::pair<std::string, double>>& one) {
  for (const auto& [name, ms] : one) {
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& x) { return x.first == name; });
    if (it == sum.end())
      sum.emplace_back(name, ms);
    else
      it->second += ms;
  }
}

}  // namespace

TileTriangulator gpu_tile_triangulator(const GpuCdt& cdt, GpuCdtStats* sum) {
  return [&cdt, sum, lock = std::make_shared<std::mutex>()](
             const std::vector<Point3>& vertices, const std::vector<Edge>& segments, std::string_view what) {
    // A tile is a resolved graph already: no resolve stage, no copies.
    // Isolated: a thread waiting inside the pipeline's own parallel loops must not pick up another tile,
    // which would wait for the lock it holds.
    return tbb::this_task_arena::isolate([&] {
      std::lock_guard<std::mutex> one_at_a_time(*lock);
      try {
        GpuCdtStats one;
        TileMesh mesh{cdt.triangulate_graph(vertices, segments, &one), {}};
        if (sum) {
          add(sum->wall_ms, one.wall_ms);
          add(sum->gpu_ms, one.gpu_ms);
          sum->gpu_total_ms += one.gpu_total_ms;
          sum->wall_total_ms += one.wall_total_ms;
          sum->peak_device_bytes = std::max(sum->peak_device_bytes, one.peak_device_bytes);
        }
        return mesh;
      } catch (const DeviceError& e) {
        throw DeviceError(std::string(what) + " (" + std::to_string(vertices.size()) + " vertices, " +
                          std::to_string(segments.size()) + " segments): " + e.what());
      }
    });
  };
}

uint64_t max_tile_points(const Context& ctx) {
  uint64_t device_local = 0;
  for (size_t h = 0; h < ctx.info.heap_sizes.size(); ++h)
    if (ctx.info.heap_device_local[h]) device_local = std::max(device_local, ctx.info.heap_sizes[h]);
  constexpr uint64_t kBytesPerPoint = 260;
  const uint64_t by_memory = device_local / kBytesPerPoint;
  const uint64_t by_slots = DT_MAX_SLOTS / 2;
  // The largest descriptor-bound buffer per point: the constraint inserter's 12-byte tables per triangle
  // slot, ~24 bytes a point (6.1 GB at 256M points, refused by a 4 GiB range).
  const uint64_t by_range = ctx.info.max_storage_buffer_range / 24;
  return std::min({by_memory, by_slots, by_range}) / 4 * 3;
}

}  // namespace cdtgpu::gpu
