// Test helper: the one Vulkan context of a GPU test executable (the Khronos validation layer on where it is
// installed), and the check that it reported nothing.
#pragma once
#include <gtest/gtest.h>

#include "gpu/context.hpp"

namespace cdtgpu::test {

inline gpu::Context& ctx() {
  static gpu::Context c = [] {
    gpu::ContextOptions options;
    options.validation = true;
    return gpu::create_context(options);
  }();
  return c;
}

// Every validation message since the last call is a test failure.
inline void no_validation_messages() {
  for (auto& m : ctx().messages()) ADD_FAILURE() << m;
  ctx().clear_messages();
}

}  // namespace cdtgpu::test
