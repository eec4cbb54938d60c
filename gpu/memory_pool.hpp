// One block of device-local memory allocated ahead, on a thread of its own, from which buffers take aligned
// ranges instead of calling vkAllocateMemory each. Tiles (gpu/tile_triangulator): the block for the largest
// tile is allocated while the resolve and the plan run on the host, instead of by the first tiles' buffers
// (3.1 s of allocation at 1B points on one H200, 8-10 s summed on two, which serialise in the driver). A
// buffer that does not fit is allocated as before.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>

namespace cdtgpu::gpu {

struct Context;

class MemoryPool {
 public:
  // Allocates `bytes` of memory type `type`; throws DeviceError when the device refuses.
  MemoryPool(const Context& ctx, VkDeviceSize bytes, uint32_t type);
  ~MemoryPool();
  MemoryPool(const MemoryPool&) = delete;
  MemoryPool& operator=(const MemoryPool&) = delete;

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
