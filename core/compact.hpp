// Parallel compaction: the items of [0, n) that count(i) says, in order, each written by emit(i, out).
//
//   std::vector<uint32_t> ids = compact<uint32_t>(n, [&](size_t i) { return keep[i]; },
//                                                 [&](size_t i, uint32_t* at) { if (keep[i]) *at++ = i; return at; });
//
// count(i) is how many items i writes (0 or more); blocks count theirs, then write at their offsets on all cores.
// compact_starts(n, count) is the counting pass alone (the blocks' offsets), for a caller writing two lists.
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "core/touched.hpp"

namespace cdtgpu {

inline constexpr size_t kCompactBlock = size_t(1) << 16;

// The first pass alone, for a caller that writes several outputs at once: block b (items [b * kCompactBlock,
// (b + 1) * kCompactBlock)) writes from [b] on, and back() is the total.
template <class Count>
std::vector<size_t> compact_starts(size_t n, Count count) {
  const size_t blocks = (n + kCompactBlock - 1) / kCompactBlock;
  std::vector<size_t> first(blocks + 1, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    for (size_t i = b * kCompactBlock; i < std::min(n, (b + 1) * kCompactBlock); ++i) first[b + 1] += count(i);
  });
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  return first;
}

// The same into a container of one's choosing: a RawVector is written once, a std::vector zeroed first.
template <class Vec, class Count, class Emit>
Vec compact_as(size_t n, Count count, Emit emit) {
  using T = typename Vec::value_type;
  const std::vector<size_t> first = compact_starts(n, count);
  const size_t blocks = first.size() - 1;
  Vec out;
  if constexpr (std::is_same_v<Vec, RawVector<T>>)
    resize_unwritten(out, first[blocks]);
  else
    resize_touched(out, first[blocks]);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    T* at = out.data() + first[b];
    for (size_t i = b * kCompactBlock; i < std::min(n, (b + 1) * kCompactBlock); ++i) at = emit(i, at);
  });
  return out;
}

template <class T, class Count, class Emit>
std::vector<T> compact(size_t n, Count count, Emit emit) {
  return compact_as<std::vector<T>>(n, count, emit);
}

}  // namespace cdtgpu
