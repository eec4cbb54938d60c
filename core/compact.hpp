// Parallel compaction: the items of [0, n) that count(i) says, in order, each written by emit(i, out).
//
//   std::vector<uint32_t> ids = compact<uint32_t>(n, [&](size_t i) { return keep[i]; },
//                                                 [&](size_t i, uint32_t* at) { if (keep[i]) *at++ = i; return at; });
//
// count(i) is how many items i writes (0 or more); blocks count theirs, then write at their offsets on all cores.
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "core/touched.hpp"

namespace cdtgpu {

// The same into a container of one's choosing: a RawVector is written once, a std::vector zeroed first.
template <class Vec, class Count, class Emit>
Vec compact_as(size_t n, Count count, Emit emit) {
  using T = typename Vec::value_type;
  constexpr size_t kBlock = 1 << 16;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<size_t> first(blocks + 1, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) first[b + 1] += count(i);
  });
  for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
  Vec out;
  if constexpr (std::is_same_v<Vec, RawVector<T>>)
    resize_unwritten(out, first[blocks]);
  else
    resize_touched(out, first[blocks]);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    T* at = out.data() + first[b];
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) at = emit(i, at);
  });
  return out;
}

template <class T, class Count, class Emit>
std::vector<T> compact(size_t n, Count count, Emit emit) {
  return compact_as<std::vector<T>>(n, count, emit);
}

}  // namespace cdtgpu
