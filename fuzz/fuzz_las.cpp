// libFuzzer target: see harness.hpp.
#include "fuzz/harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  cdtgpu::fuzz::fuzz_las(data, size);
  return 0;
}
