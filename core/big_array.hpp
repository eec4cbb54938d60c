// BigArray: a fixed-size array for large, short-lived working buffers of the parallel passes.
//
//   BigArray<uint32_t> root(T);         // not zeroed: the first pass writes every element
//   BigArray<uint8_t> flag(3 * T, 0);   // filled on all cores
//
// std::vector zeroes its elements on one core, and the first write to each 4 KiB page faults: at millions of
// elements that serial zeroing and faulting cost more than the pass itself. Here nothing is written up front
// (or the fill runs on all cores, spreading the faults), and buffers of 4 MiB and more ask the kernel for
// transparent huge pages (2 MiB: 512 times fewer faults) where it allows them (madvise mode).
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/touched.hpp"

namespace cdtgpu {

template <class T>
class BigArray {
  // Implicit-lifetime types only: elements are assigned into raw storage, never constructed.
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  BigArray() = default;
  explicit BigArray(size_t n) : data_(allocate(n)), size_(n) {}
  BigArray(size_t n, const T& value) : BigArray(n) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      std::uninitialized_fill(data_.get() + r.begin(), data_.get() + r.end(), value);
    });
  }

  T& operator[](size_t i) { return data_.get()[i]; }
  const T& operator[](size_t i) const { return data_.get()[i]; }
  size_t size() const { return size_; }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size_; }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  static T* allocate(size_t n) {
    constexpr size_t kHuge = size_t(2) << 20;
    const size_t bytes = n * sizeof(T);
    void* p = nullptr;
    if (bytes >= 2 * kHuge) {
      const size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
      p = std::aligned_alloc(kHuge, rounded);
      if (p) advise_huge_pages(p, rounded);
    } else {
      p = std::malloc(bytes ? bytes : 1);
    }
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }

  std::unique_ptr<T, Free> data_;
  size_t size_ = 0;
};

}  // namespace cdtgpu
