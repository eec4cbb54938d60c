// Triangles in order where they lie: spans of the arrays that hold them, one after another. A tiled run's
// canonical order is its tiles' sorted runs and its merge's, interleaved (core/tile_merge, RunMerge::in_place);
// a mesh writer reads them in place through this instead of their copy into one array (24 GB at 1B points).
//
//   TriangleSpans all(mesh.triangles);                  // one array: one span
//   all.each(first, count, [&](std::span<const Triangle> s) { ... });   // [first, first + count), in order
//   OrderedRuns o = order.in_place(std::move(runs));    // the runs and their spans; o.spans() for a writer
//   Triangles one = std::move(o).take();                // one array, for what reads the mesh whole
#pragma once
#include <algorithm>
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

class TriangleSpans {
 public:
  TriangleSpans() = default;
  explicit TriangleSpans(std::span<const Triangle> all) {
    if (!all.empty()) spans_.push_back(all), at_.push_back(all.size());
  }
  explicit TriangleSpans(std::vector<std::span<const Triangle>> spans) : spans_(std::move(spans)) {
    at_.reserve(spans_.size() + 1);
    for (const auto& s : spans_) at_.push_back(at_.back() + s.size());
  }
  // With their places made already (at: spans.size() + 1 of them, from 0), as RunMerge::in_place makes them
  // on all cores (4.4M spans at 100M points + 25M contour vertices).
  TriangleSpans(std::vector<std::span<const Triangle>> spans, std::vector<size_t> at)
      : spans_(std::move(spans)), at_(std::move(at)) {}

  size_t size() const { return at_.back(); }
  bool empty() const { return size() == 0; }
  size_t span_count() const { return spans_.size(); }

  // f(span) for the triangles [first, first + count) (within size()), in order, no span empty.
  template <class F>
  void each(size_t first, size_t count, F&& f) const {
    if (count == 0) return;
    size_t k = size_t(std::upper_bound(at_.begin(), at_.end(), first) - at_.begin()) - 1;
    for (size_t off = first - at_[k]; count > 0; ++k, off = 0) {
      const std::span<const Triangle> s = spans_[k].subspan(off, std::min(count, spans_[k].size() - off));
      f(s);
      count -= s.size();
    }
  }

 private:
  std::vector<std::span<const Triangle>> spans_;
  std::vector<size_t> at_{0};  // at_[k]: the place of spans_[k]'s first triangle; at_.back(): size()
};

// Triangles in order, held by the arrays they were made in (`runs`), read through `spans`, which lie in them.
class OrderedRuns {
 public:
  OrderedRuns() = default;
  explicit OrderedRuns(Triangles&& one);
  OrderedRuns(std::vector<Triangles>&& runs, TriangleSpans spans) : runs_(std::move(runs)), spans_(std::move(spans)) {}
  // Moved, the arrays keep their storage: the spans stay valid.
  OrderedRuns(OrderedRuns&&) = default;
  OrderedRuns& operator=(OrderedRuns&&) = default;

  const TriangleSpans& spans() const { return spans_; }
  size_t size() const { return spans_.size(); }
  bool empty() const { return spans_.empty(); }
  // The triangles as one array: the one run itself where it is all of them, else copied on all cores and the
  // runs freed. Leaves this empty.
  Triangles take() &&;

 private:
  std::vector<Triangles> runs_;
  TriangleSpans spans_;
};

}  // namespace cdtgpu
