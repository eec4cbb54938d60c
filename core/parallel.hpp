// Small loops over an index range on all cores, for the passes of core/regions and gpu/voronoi_check.
//
//   each(n, [&](size_t i) { ... });                       // f(i) for every i < n
//   uint64_t k = count_if(n, [&](size_t i) { return keep[i]; });
//   prefix_sums(first);                                   // counts in first[1..] -> offsets
//   shared(x).fetch_add(1, std::memory_order_relaxed);    // an element written by several threads
//   group(m, buckets, [&](size_t i) { return key[i]; }, first, items);   // items by key: a counting sort
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <type_traits>

#include "core/uninit.hpp"

namespace cdtgpu {

inline constexpr size_t kParallelGrain = 1 << 14;

template <class T>
std::atomic_ref<T> shared(T& x) {
  return std::atomic_ref<T>(x);
}

template <class F>
void each(size_t n, F&& f, size_t grain = kParallelGrain) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) f(i);
  });
}

template <class F>
uint64_t count_if(size_t n, F&& f, size_t grain = kParallelGrain) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, grain), uint64_t(0),
      [&](const tbb::blocked_range<size_t>& r, uint64_t sum) {
        for (size_t i = r.begin(); i < r.end(); ++i) sum += f(i) ? 1 : 0;
        return sum;
      },
      std::plus<uint64_t>());
}

// std::copy of n items in 1 MB blocks on all cores when large: one core copies ~5 GB/s on the H100 machine,
// and fresh destination pages are faulted where they are written.
template <class T>
void copy_on_all_cores(const T* from, size_t n, T* to) {
  static_assert(std::is_trivially_copyable_v<T>);
  constexpr size_t kBlock = std::max<size_t>(1, (size_t(1) << 20) / sizeof(T));
  if (n < 8 * kBlock) {
    std::copy(from, from + n, to);
    return;
  }
  tbb::parallel_for(size_t(0), (n + kBlock - 1) / kBlock, [&](size_t b) {
    std::copy(from + b * kBlock, from + std::min(n, (b + 1) * kBlock), to + b * kBlock);
  });
}

// first[0] = 0 and first[i + 1] a count for item i: afterwards first[i] is the sum of the counts before i (so
// item i's range is [first[i], first[i + 1])).
template <class Array>
void prefix_sums(Array& first, size_t grain = kParallelGrain) {
  using T = std::remove_reference_t<decltype(first[0])>;
  tbb::parallel_scan(
      tbb::blocked_range<size_t>(1, first.size(), grain), T(0),
      [&](const tbb::blocked_range<size_t>& r, T sum, bool final) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          sum += first[i];
          if (final) first[i] = sum;
        }
        return sum;
      },
      std::plus<T>());
}

// Items 0 .. m - 1 grouped by key(i) < buckets: group b is items[first[b] .. first[b + 1]), ascending (the
// order a serial counting sort gives, whatever order the cores scattered them in); in the order the cores
// scattered them where `ascending` is false (for callers that sort or search a group by something else).
template <class Key>
void group(size_t m, size_t buckets, Key&& key, RawVector<uint32_t>& first, RawVector<uint32_t>& items,
           bool ascending = true) {
  first.resize(buckets + 1);
  each(buckets + 1, [&](size_t b) { first[b] = 0; });
  each(m, [&](size_t i) { shared(first[key(i) + 1]).fetch_add(1, std::memory_order_relaxed); });
  prefix_sums(first);
  RawVector<uint32_t> cursor(buckets);
  each(buckets, [&](size_t b) { cursor[b] = first[b]; });
  items.resize(m);
  each(m, [&](size_t i) { items[shared(cursor[key(i)]).fetch_add(1, std::memory_order_relaxed)] = uint32_t(i); });
  if (ascending) each(buckets, [&](size_t b) { std::sort(items.begin() + first[b], items.begin() + first[b + 1]); });
}

}  // namespace cdtgpu
