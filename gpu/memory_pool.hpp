// One block of device-local memory allocated ahead (on another thread, while the input is read), from which
// buffers take aligned ranges instead of calling vkAllocateMemory each: allocation costs about 35 us per MiB
// on the lent H100 machine, ~26 ms of a 2.5M-point triangulation's wall clock and ~70 ms at 5M, all of it on
// the critical path. A buffer that does not fit (an input larger than guessed) is allocated as before.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>

namespace cdtgpu::gpu {

struct Context;

class DevicePool {
 public:
  // Allocates `bytes` of memory type `type`; throws DeviceError when the device refuses.
  DevicePool(const Context& ctx, VkDeviceSize bytes, uint32_t type);
  ~DevicePool();
  DevicePool(const DevicePool&) = delete;
  DevicePool& operator=(const DevicePool&) = delete;

  // First fit: the offset of a range of `size` bytes at `alignment`, or none when no free range holds it.
  std::optional<VkDeviceSize> take(VkDeviceSize size, VkDeviceSize alignment);
  // Gives a range back; it merges with free neighbours.
  void give(VkDeviceSize offset, VkDeviceSize size);

  VkDeviceMemory memory() const { return memory_; }
  uint32_t type() const { return type_; }
  VkDeviceSize free_bytes() const;

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  uint32_t type_ = 0;
  mutable std::mutex mutex_;
  std::map<VkDeviceSize, VkDeviceSize> free_;  // offset -> size, no two adjacent
};

}  // namespace cdtgpu::gpu
