// A counting sort on one core, for lists sorted where they lie in cache or on a worker's own core: prepare's
// buckets (core/merge_points.cpp, core/prepare.cpp) and a CPU tile's triangles (core/canonical.cpp).
//
//   counting_sort(in, m, out, keys, [](const T& x) { return key_of(x); }, starts);
//   // group k is out[starts[k] .. starts[k + 1])
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace cdtgpu {

// in[0, m) copied to out grouped by key(x) < keys, in input order within a group (m below 2^32).
template <class T, class Key>
void counting_sort(const T* in, size_t m, T* out, size_t keys, const Key& key, std::vector<uint32_t>& starts) {
  starts.assign(keys + 1, 0);
  for (size_t i = 0; i < m; ++i) ++starts[key(in[i]) + 1];
  std::partial_sum(starts.begin(), starts.end(), starts.begin());
  for (size_t i = 0; i < m; ++i) out[starts[key(in[i])]++] = in[i];
  // Each group's start has moved to its end, the next one's start: moved back.
  if (keys > 1) std::copy_backward(starts.begin(), starts.begin() + (keys - 1), starts.begin() + keys);
  starts[0] = 0;
}

}  // namespace cdtgpu
