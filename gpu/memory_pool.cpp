#include "gpu/memory_pool.hpp"

#include "gpu/check.hpp"
#include "gpu/context.hpp"

namespace cdtgpu::gpu {

DevicePool::DevicePool(const Context& ctx, VkDeviceSize bytes, uint32_t type) : device_(ctx.device), type_(type) {
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  ai.allocationSize = bytes;
  ai.memoryTypeIndex = type;
  const VkResult r = vkAllocateMemory(device_, &ai, nullptr, &memory_);
  if (r != VK_SUCCESS) vk_fail(r, "vkAllocateMemory for the device memory pool", __FILE__, __LINE__);
  free_[0] = bytes;
}

DevicePool::~DevicePool() {
  if (memory_) vkFreeMemory(device_, memory_, nullptr);
}

std::optional<VkDeviceSize> DevicePool::take(VkDeviceSize size, VkDeviceSize alignment) {
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

void DevicePool::give(VkDeviceSize offset, VkDeviceSize size) {
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

VkDeviceSize DevicePool::free_bytes() const {
  std::lock_guard lock(mutex_);
  VkDeviceSize total = 0;
  for (const auto& [offset, size] : free_) total += size;
  return total;
}

}  // namespace cdtgpu::gpu
