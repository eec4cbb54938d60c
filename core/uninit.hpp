// UninitAllocator and RawVector: std::vector storage whose resize() leaves new elements unwritten.
#pragma once
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace cdtgpu {

// An allocator whose resize() writes nothing into new elements of an implicit-lifetime type (objects arise
// in the allocated storage): the readers fill hundreds of millions of points on all cores, and
// std::vector's value-initialisation would first zero them on one core (2.4 GB at 10^8 cells: ~110 ms).
// Elements constructed with arguments (push_back, emplace_back) are constructed as usual.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  UninitAllocator() = default;
  template <class U>
  UninitAllocator(const UninitAllocator<U>&) noexcept {}
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) > 0) ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// RawVector: growable buffers (points, working arrays of the parallel passes) that the caller fills after a
// resize, on all cores: the first touch of their pages then happens there, not in one serial zeroing.
template <class T>
using RawVector = std::vector<T, UninitAllocator<T>>;

// Frees a container's storage now: `v = {}` assigns an empty list and keeps the capacity, `v.clear()` too.
template <class V>
void free_storage(V& v) {
  V().swap(v);
}

template <class A>
inline constexpr bool is_uninit_allocator = false;
template <class T>
inline constexpr bool is_uninit_allocator<UninitAllocator<T>> = true;

}  // namespace cdtgpu
