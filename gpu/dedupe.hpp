// Merges exact duplicate points on the GPU: a stable radix sort by (x, y) (two 64-bit passes: y, then x), a
// flag where the sorted point changes, a scan, a scatter. The vertices come out in canonical order (sorted by x,
// then y), the same as core/prepare on the CPU, with the mapping kept: map[input point] = vertex, and
// first[vertex] = the lowest input index that landed on it (whose z the vertex takes). -0.0 equals +0.0.
// Cost: two 64-bit key sorts of n points (8 passes each) plus three light passes; 48 bytes of scratch per point.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "core/prepare.hpp"
#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/recorder.hpp"

namespace cdtgpu::gpu {

struct DedupedPoints {
  Buffer xy;     // double x, y per vertex, canonical order
  Buffer map;    // uint per input point: its vertex
  Buffer first;  // uint per vertex: first input point merged into it
  uint32_t count = 0;
};

class PointDeduper {
 public:
  PointDeduper(const Context& ctx, const Primitives& prims);
  // `xy` holds n points as double pairs. Submits and waits (the vertex count sizes what follows).
  DedupedPoints run(const Buffer& xy, uint32_t n) const;
  const Context& context() const { return ctx_; }

 private:
  const Context& ctx_;
  const Primitives& prims_;
  Pass keys_, flags_, scatter_;
};

// Host-side convenience for tests and callers without buffers: the vertices, map and first occurrences.
struct DedupedHost {
  std::vector<double> xy;
  std::vector<uint32_t> map, first;
};
DedupedHost dedupe_points(const Context& ctx, std::span<const double> xy);

// core's PointMerger on the GPU, for prepare(in, merger): the same answer as cdtgpu::merge_points (upload,
// PointDeduper, download of the map and first occurrences). The GPU backend merges this way (GpuCdt::merger).
PointMerge merge_points(const PointDeduper& deduper, std::span<const double> xy);

}  // namespace cdtgpu::gpu
