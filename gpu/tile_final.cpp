#include "gpu/tile_final.hpp"

#include <algorithm>
#include <cmath>

#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

TileFinalPasses::TileFinalPasses(const Context& ctx)
    : ctx_(ctx),
      final_(create_pass(ctx, {"tile_final", 3, sizeof(TileFinalPush)})),
      border_(create_pass(ctx, {"tile_border", 5, sizeof(TileFinalPush)})) {}

std::vector<Edge> TileFinalPasses::mark(GpuTriangulation& tri, const TileRect& rect, BufferCache& cache,
                                        double* gpu_ms) const {
  if (gpu_ms) *gpu_ms = 0;
  const uint32_t slots = tri.num_slots;
  if (slots == 0) return {};
  TileFinalPush push{rect.x0, rect.x1, rect.y0, rect.y1, slots, 0, 0, 0};
  push.sides = (std::isfinite(rect.x0) ? TILE_SIDE_X0 : 0u) | (std::isfinite(rect.x1) ? TILE_SIDE_X1 : 0u) |
               (std::isfinite(rect.y0) ? TILE_SIDE_Y0 : 0u) | (std::isfinite(rect.y1) ? TILE_SIDE_Y1 : 0u);
  const uint64_t groups = (uint64_t(slots) + TILE_WG - 1) / TILE_WG;
  // "slots x4 e": no stage between the constraints and the sort holds it (the sort takes a and b).
  const Buffer& flags = cache.get(ctx_, kSlots4[4], uint64_t(slots) * 4, "tile final flags");
  const Buffer& count = cache.get(ctx_, "tile border count", 4);
  // The border is about the tile's perimeter; a run past this is run again at the size it needed.
  uint32_t capacity = std::max<uint32_t>(1u << 14, slots / 16);
  for (int attempt = 0;; ++attempt) {
    const Buffer& border = cache.get(ctx_, "tile border", uint64_t(capacity) * sizeof(Edge));
    push.capacity = capacity;
    Recorder rec(ctx_);
    Profiler prof(ctx_, 1);
    prof.begin(rec, "tile final");
    rec.fill(count, 0);
    if (attempt == 0) rec.dispatch_groups(final_, {tri.points, tri.verts, flags}, push, groups);
    rec.dispatch_groups(border_, {tri.verts, tri.nbrs, flags, border, count}, push, groups);
    prof.end(rec);
    rec.submit();
    if (gpu_ms) *gpu_ms += prof.results().front().ms;
    uint32_t found = 0;
    download(ctx_, count, &found, 4);
    if (found <= capacity) {
      std::vector<Edge> edges(found);
      if (found) download(ctx_, border, edges.data(), uint64_t(found) * sizeof(Edge));
      return edges;
    }
    capacity = found;
  }
}

}  // namespace cdtgpu::gpu
