// Sizing large vectors with their pages touched on all cores. A fresh vector of 50 MB costs more in page faults
// (the kernel zeroes each page on first touch) than in the copy that fills it, and std::vector::resize touches
// every page on one core: 33 ms for a 2M-point triangulation's triangle array on the H100 machine.
#pragma once
#include <tbb/parallel_for.h>

#include <cstring>
#include <type_traits>
#include <vector>

namespace cdtgpu {

// v.resize(n), the new elements value-initialised (zero bytes: Point3, Triangle, integers), those kept kept.
template <class T>
void resize_touched(std::vector<T>& v, size_t n) {
  static_assert(std::is_trivially_copyable_v<T>);
  if (n <= v.capacity() || n * sizeof(T) < (size_t(8) << 20)) {
    v.resize(n);
    return;
  }
  v.reserve(n);
  // Zero bytes in freshly allocated storage past the elements kept (implicitly created objects), page by page
  // on all cores; the resize below then writes over memory that is already there.
  char* base = reinterpret_cast<char*>(v.data() + v.size());
  const size_t bytes = (n - v.size()) * sizeof(T), block = size_t(1) << 20;
  tbb::parallel_for(size_t(0), (bytes + block - 1) / block, [&](size_t b) {
    std::memset(base + b * block, 0, std::min(block, bytes - b * block));
  });
  v.resize(n);
}

}  // namespace cdtgpu
