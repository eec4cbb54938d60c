#include "gpu/memory_pool.hpp"

#include "gpu/check.hpp"
#include "gpu/context.hpp"

namespace cdtgpu::gpu {

MemoryPool::MemoryPool(const Context& ctx, VkDeviceSize bytes, uint32_t type) : device_(ctx.device), type_(type) {
  // Addressed buffers (gpu/buffers.hpp) bind into it too.
  VkMemoryAllocateFlagsInfo flags{};
  flags.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO;
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  ai.pNext = &flags;
  ai.allocationSize = bytes;
  ai.memoryTypeIndex = type;
  const VkResult r = vkAllocateMemory(device_, &ai, nullptr, &memory_);
  if (r != VK_SUCCESS) vk_fail(r, "vkAllocateMemory for the device memory pool", __FILE__, __LINE__);
  free_[0] = bytes;
}

MemoryPool::~MemoryPool() {
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
}

std::optional<VkDeviceSize> MemoryPool::take(VkDeviceSize size, VkDeviceSize alignment) {
  std::lock_guard lock(mutex_);
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    const VkDeviceSize start = it->first, end = it->first + it->second;
    const VkDeviceSize at = (start + alignment - 1) / alignment * alignment;
    if (at + size > end) continue;
    free_.erase(it);
    if (at > start) free_[start] = at - start;
    if (at + size < end) free_[at + size] = end - (at + size);
    return at;
  }
  return std::nullopt;
}

void MemoryPool::give(VkDeviceSize offset, VkDeviceSize size) {
  std::lock_guard lock(mutex_);
  auto next = free_.lower_bound(offset);
  if (next != free_.end() && offset + size == next->first) {  // merge with the range after
    size += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {  // and with the range before
    auto prev = std::prev(next);
    if (prev->first + prev->second == offset) {
      prev->second += size;
      return;
    }
  }
  free_[offset] = size;
}

VkDeviceSize MemoryPool::free_bytes() const {
  std::lock_guard lock(mutex_);
  VkDeviceSize total = 0;
  for (const auto& [offset, size] : free_) total += size;
  return total;
}

}  // namespace cdtgpu::gpu
