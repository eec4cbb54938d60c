// Milliseconds since a moment on the steady clock: stage times, and the -v lines that report them.
#pragma once
#include <chrono>

namespace cdtgpu {

inline double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace cdtgpu
