// The duplicate merge's reference answer for the tests: input indices stably sorted by (x, y) with == as
// equality (so -0.0 == 0.0); a vertex where (x, y) changes.
#pragma once
#include <algorithm>
#include <numeric>
#include <vector>

#include "core/prepare.hpp"

namespace cdtgpu {

inline PointMerge stable_sort_merge(const std::vector<double>& xy) {
  const size_t n = xy.size() / 2;
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](uint32_t a, uint32_t b) {
    return xy[2 * a] < xy[2 * b] || (xy[2 * a] == xy[2 * b] && xy[2 * a + 1] < xy[2 * b + 1]);
  };
  std::stable_sort(order.begin(), order.end(), less);
  PointMerge m;
  m.vertex_of.resize(n);
  for (size_t i = 0; i < n; ++i) {
    if (i == 0 || less(order[i - 1], order[i])) m.first.push_back(order[i]);
    m.vertex_of[order[i]] = uint32_t(m.first.size() - 1);
  }
  return m;
}

}  // namespace cdtgpu
