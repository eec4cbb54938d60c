// Sizing large vectors with their pages touched on all cores. A fresh vector of 50 MB costs more in page faults
// (the kernel zeroes each page on first touch) than in the copy that fills it, and std::vector::resize touches
// every page on one core: 33 ms for a 2M-point triangulation's triangle array on the H100 machine.
#pragma once
#include <sys/mman.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <algorithm>
#include <cstring>
#include <type_traits>
#include <vector>

#include "core/uninit.hpp"

namespace cdtgpu {

// Asks for transparent huge pages (2 MiB: 512 times fewer faults) on the whole 2 MiB pages inside
// [p, p + bytes), where the kernel allows them (madvise mode). 520 MB of points on 2 cores: touched in 135 ms
// with 4 KiB pages, 27-38 ms with huge ones. Advice only: without it, 4 KiB pages.
inline void advise_huge_pages(void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t first = (uintptr_t(p) + kHuge - 1) & ~(kHuge - 1), end = (uintptr_t(p) + bytes) & ~(kHuge - 1);
  if (end > first) madvise(reinterpret_cast<void*>(first), end - first, MADV_HUGEPAGE);
}

// Gives the whole pages inside [p, p + bytes) back to the system (their contents are dead; a page touched again
// comes back zeroed); the allocation stays. One call over 512 MB of 4 KiB pages took 19 ms on one core of the
// 2-core development machine, so large ranges go in 64 MB pieces on all cores.
inline void release_pages(const void* p, size_t bytes) {
  constexpr uintptr_t kPage = 4096, kPiece = uintptr_t(64) << 20;
  const uintptr_t a = (uintptr_t(p) + kPage - 1) & ~(kPage - 1), b = (uintptr_t(p) + bytes) & ~(kPage - 1);
  if (b <= a) return;
  const size_t pieces = (b - a + kPiece - 1) / kPiece;
  auto piece = [&](size_t i) {
    const uintptr_t from = a + i * kPiece, to = std::min(b, from + kPiece);
    madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED);
  };
  if (pieces == 1) return piece(0);
  tbb::parallel_for(size_t(0), pieces, size_t(1), piece);
}

// free_storage (core/uninit.hpp) of a large vector, its pages given back on all cores first: the free then
// finds them gone (one munmap of 1 GB in 4 KiB pages: ~40 ms on one core).
template <class V>
void free_storage_on_all_cores(V& v) {
  release_pages(v.data(), v.size() * sizeof(typename V::value_type));
  free_storage(v);
}

// Zeroes [p, p + bytes) in 2 MiB pieces on all cores: the first touch of fresh pages is spread over them.
inline void zero_on_all_cores(void* p, size_t bytes) {
  constexpr size_t kPiece = size_t(2) << 20;
  char* base = static_cast<char*>(p);
  tbb::parallel_for(size_t(0), (bytes + kPiece - 1) / kPiece, [&](size_t b) {
    std::memset(base + b * kPiece, 0, std::min(kPiece, bytes - b * kPiece));
  });
}

// v.resize(n), the new elements zero (value-initialised: Point3, Triangle, integers), those kept kept; the new
// pages zeroed on all cores, on huge pages. std::vector's own resize then writes the zeros once more on one
// core (1 s for 6 GB on the H100 machine); a RawVector's does not.
template <class T, class A>
void resize_touched(std::vector<T, A>& v, size_t n) {
  static_assert(std::is_trivially_copyable_v<T>);
  constexpr bool raw = is_uninit_allocator<A>;
  const size_t kept = std::min(n, v.size()), bytes = (n - kept) * sizeof(T);
  if (bytes < (size_t(8) << 20) || (!raw && n <= v.capacity())) {
    v.resize(n);
    if constexpr (raw) std::memset(static_cast<void*>(v.data() + kept), 0, bytes);  // its resize wrote nothing
    return;
  }
  if (n > v.capacity()) {
    v.reserve(n);
    advise_huge_pages(v.data() + kept, bytes);
  }
  zero_on_all_cores(v.data() + kept, bytes);
  v.resize(n);
}

// v = {f(0), ..., f(n - 1)} with room for `capacity` elements, on all cores: the new storage's pages faulted
// and the elements written there (std::vector's resize then zeroes them once more on one core, on pages already
// there). One core's assign, iota or reallocating reserve took ~1 s for 250M elements with its page faults.
template <class T, class F>
void assign_on_all_cores(std::vector<T>& v, size_t n, size_t capacity, F&& f) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<T> out;
  out.reserve(std::max(n, capacity));
  advise_huge_pages(out.data(), out.capacity() * sizeof(T));
  zero_on_all_cores(out.data(), n * sizeof(T));
  out.resize(n);
  constexpr size_t kBlock = (size_t(2) << 20) / sizeof(T) + 1;
  tbb::parallel_for(size_t(0), (n + kBlock - 1) / kBlock, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) out[i] = f(i);
  });
  v.swap(out);
}

// v.reserve(capacity), a reallocation's copy made on all cores (assign_on_all_cores).
template <class T>
void reserve_on_all_cores(std::vector<T>& v, size_t capacity) {
  if (capacity <= v.capacity()) return;
  if (v.size() * sizeof(T) < (size_t(8) << 20)) return v.reserve(capacity);
  const T* from = v.data();
  assign_on_all_cores(v, v.size(), capacity, [from](size_t i) { return from[i]; });
}

// v.resize(n) for a RawVector, the new elements left for the caller to write, on all cores: their pages are
// faulted by those writes, on huge pages. Writing each element once is all the work.
template <class T>
void resize_unwritten(RawVector<T>& v, size_t n) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (n > v.capacity() && n * sizeof(T) >= (size_t(8) << 20)) {
    v.reserve(n);
    advise_huge_pages(v.data() + v.size(), (n - v.size()) * sizeof(T));
  }
  v.resize(n);
}

}  // namespace cdtgpu
