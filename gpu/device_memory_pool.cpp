#include "gpu/device_memory_pool.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "gpu/context.hpp"

namespace cdtgpu::gpu {

FreeRanges::FreeRanges(uint64_t size) {
  if (size) free_[0] = size;
}

std::optional<uint64_t> FreeRanges::take(uint64_t bytes, uint64_t alignment) {
  bytes = std::max<uint64_t>(bytes, 1);
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    const uint64_t start = it->first, end = it->first + it->second;
    const uint64_t at = (start + alignment - 1) / alignment * alignment;
    if (at + bytes > end) continue;
    free_.erase(it);
    if (at > start) free_[start] = at - start;
    if (at + bytes < end) free_[at + bytes] = end - (at + bytes);
    return at;
  }
  return std::nullopt;
}

void FreeRanges::give(uint64_t offset, uint64_t bytes) {
  bytes = std::max<uint64_t>(bytes, 1);
  auto next = free_.lower_bound(offset);
  if (next != free_.begin()) {  // merged with the range before it where they touch
    auto prev = std::prev(next);
    if (prev->first + prev->second == offset) {
      offset = prev->first;
      bytes += prev->second;
      free_.erase(prev);
    }
  }
  if (next != free_.end() && offset + bytes == next->first) {
    bytes += next->second;
    free_.erase(next);
  }
  free_[offset] = bytes;
}

uint64_t FreeRanges::free_bytes() const {
  uint64_t n = 0;
  for (const auto& [offset, size] : free_) n += size;
  return n;
}

DeviceMemoryPool::DeviceMemoryPool(const Context& ctx, uint64_t bytes, uint64_t block_bytes, uint32_t type, bool addressed)
    : device_(ctx.device), type_(type) {
  const auto t0 = std::chrono::steady_clock::now();
  VkMemoryAllocateFlagsInfo flags{};
  flags.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO;
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  while (bytes_ < bytes && block_bytes) {
    VkMemoryAllocateInfo ai{};
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    if (addressed) ai.pNext = &flags;
    ai.allocationSize = std::min(block_bytes, bytes - bytes_);
    ai.memoryTypeIndex = type;
    VkDeviceMemory m = VK_NULL_HANDLE;
    if (vkAllocateMemory(device_, &ai, nullptr, &m) != VK_SUCCESS) break;  // the rest made as needed
    blocks_.push_back(m);
    free_.emplace_back(ai.allocationSize);
    bytes_ += ai.allocationSize;
  }
  spdlog::debug("device memory pool: {:.0f} MB in {} block(s) made in {:.1f} ms", bytes_ / 1e6, blocks_.size(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
}

std::optional<DeviceMemoryPool::Range> DeviceMemoryPool::take(const VkMemoryRequirements& req) {
  if (!(req.memoryTypeBits & (1u << type_))) return std::nullopt;
  std::lock_guard lock(mutex_);
  for (size_t b = 0; b < blocks_.size(); ++b)
    if (auto at = free_[b].take(req.size, std::max<uint64_t>(req.alignment, 1))) {
      taken_.fetch_add(1);
      return Range{blocks_[b], uint32_t(b), *at, req.size};
    }
  return std::nullopt;
}

void DeviceMemoryPool::give(const Range& r) {
  std::lock_guard lock(mutex_);
  if (r.block < free_.size()) free_[r.block].give(r.offset, r.bytes);
}

uint64_t DeviceMemoryPool::free_bytes() {
  std::lock_guard lock(mutex_);
  uint64_t n = 0;
  for (const FreeRanges& f : free_) n += f.free_bytes();
  return n;
}

void DeviceMemoryPool::free_blocks() {
  std::lock_guard lock(mutex_);
  for (VkDeviceMemory m : blocks_) vkFreeMemory(device_, m, nullptr);
  blocks_.clear();
  free_.clear();
}

}  // namespace cdtgpu::gpu
