// OrderedRuns (core/triangle_spans.hpp).
#include "core/triangle_spans.hpp"

#include <tbb/parallel_for.h>

#include <cstring>

#include "core/touched.hpp"

namespace cdtgpu {

OrderedRuns::OrderedRuns(Triangles&& one) {
  runs_.push_back(std::move(one));
  spans_ = TriangleSpans(std::span<const Triangle>(runs_[0].data(), runs_[0].size()));
}

Triangles OrderedRuns::take() && {
  Triangles out;
  if (runs_.size() == 1 && spans_.span_count() <= 1 && spans_.size() == runs_[0].size()) {  // the span is the run
    out = std::move(runs_[0]);
  } else {
    resize_unwritten(out, spans_.size());
    constexpr size_t kBlock = size_t(1) << 20;
    tbb::parallel_for(size_t(0), (out.size() + kBlock - 1) / kBlock, [&](size_t b) {
      Triangle* to = out.data() + b * kBlock;
      spans_.each(b * kBlock, std::min(kBlock, out.size() - b * kBlock), [&](std::span<const Triangle> s) {
        std::memcpy(static_cast<void*>(to), s.data(), s.size_bytes());
        to += s.size();
      });
    });
    tbb::parallel_for(size_t(0), runs_.size(), [&](size_t r) { free_storage_on_all_cores(runs_[r]); });
  }
  *this = OrderedRuns();
  return out;
}

}  // namespace cdtgpu
