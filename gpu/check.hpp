// VK_CHECK and the GPU error types: a failed Vulkan call becomes an exception naming the call and file:line.
#pragma once
#include <vulkan/vulkan.h>

#include <stdexcept>
#include <string>

namespace cdtgpu::gpu {

// The device cannot do what was asked (missing feature, buffer over a limit, no device at all).
struct DeviceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The work is more than the device holds (a buffer beyond its range or its memory): smaller pieces may fit.
// need / limit: how far over, where known (0 when not).
struct TooLarge : DeviceError {
  TooLarge(const std::string& what, double need = 0, double limit = 0) : DeviceError(what), need(need), limit(limit) {}
  double need, limit;
};

// A Vulkan call failed. `result` is the VkResult; out-of-memory and device-lost are named as such.
struct VulkanError : DeviceError {
  VulkanError(VkResult result, const std::string& what) : DeviceError(what), result(result) {}
  VkResult result;
};

// Whether smaller work might fit: TooLarge, or the driver out of device memory.
inline bool too_large(const DeviceError& e) {
  if (dynamic_cast<const TooLarge*>(&e)) return true;
  const auto* v = dynamic_cast<const VulkanError*>(&e);
  return v && v->result == VK_ERROR_OUT_OF_DEVICE_MEMORY;
}

inline const char* result_name(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY (out of host memory)";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY (out of GPU memory)";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST (GPU device lost: crash, hang or driver reset)";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER (no Vulkan driver)";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_FRAGMENTED_POOL: return "VK_ERROR_FRAGMENTED_POOL";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    default: return "VkResult";
  }
}

[[noreturn]] inline void vk_fail(VkResult r, const char* call, const char* file, int line) {
  std::string m = "Vulkan call ";
  m += call;
  m += " failed with ";
  m += result_name(r);
  m += " (";
  m += std::to_string(static_cast<int>(r));
  m += ") at ";
  m += file;
  m += ':';
  m += std::to_string(line);
  throw VulkanError(r, m);
}

}  // namespace cdtgpu::gpu

#define VK_CHECK(call)                                                          \
  do {                                                                          \
    VkResult vk_check_result_ = (call);                                         \
    if (vk_check_result_ != VK_SUCCESS)                                         \
      ::cdtgpu::gpu::vk_fail(vk_check_result_, #call, __FILE__, __LINE__);      \
  } while (0)
