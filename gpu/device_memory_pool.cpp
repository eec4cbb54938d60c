#include "gpu/device_memory_pool.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "core/timing.hpp"
#include "gpu/context.hpp"

namespace cdtgpu::gpu {

FreeRanges::FreeRanges(uint64_t size) {
  if (size) free_[0] = size;
}

namespace {
// The range of `free` that `bytes` at `alignment` leaves least of (the lowest of equals; end where none fits),
// the offset it would take there, and what it would leave.
template <class Map>
auto best_fit(Map& free, uint64_t bytes, uint64_t alignment) {
  struct Fit {
    decltype(free.end()) range;
    uint64_t at, left;
  } best{free.end(), 0, 0};
  for (auto it = free.begin(); it != free.end(); ++it) {
    const uint64_t at = (it->first + alignment - 1) / alignment * alignment, end = it->first + it->second;
    if (at + bytes > end) continue;
    if (best.range == free.end() || end - (at + bytes) < best.left) best = {it, at, end - (at + bytes)};
  }
  return best;
}
}  // namespace

std::optional<uint64_t> FreeRanges::fit(uint64_t bytes, uint64_t alignment) const {
  const auto best = best_fit(free_, std::max<uint64_t>(bytes, 1), alignment);
  return best.range == free_.end() ? std::nullopt : std::optional<uint64_t>(best.left);
}

std::optional<uint64_t> FreeRanges::take(uint64_t bytes, uint64_t alignment) {
  bytes = std::max<uint64_t>(bytes, 1);
  const auto [it, at, left] = best_fit(free_, bytes, alignment);
  if (it == free_.end()) return std::nullopt;
  const uint64_t start = it->first;
  free_.erase(it);
  if (at > start) free_[start] = at - start;
  if (left) free_[at + bytes] = left;
  return at;
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
    : device_(ctx.device), type_(type), block_bytes_(block_bytes), addressed_(addressed) {
  const auto t0 = std::chrono::steady_clock::now();
  while (bytes_.load() < bytes && block_bytes && add_block(std::min(block_bytes, bytes - bytes_.load()))) {
  }
  const double ms = ms_since(t0);
  spdlog::debug("device memory pool: {:.0f} MB in {} block(s) made in {:.1f} ms", bytes_.load() / 1e6,
                blocks_.size(), ms);
}

bool DeviceMemoryPool::add_block(uint64_t size) {
  VkMemoryAllocateFlagsInfo flags{};
  flags.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO;
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  if (addressed_) ai.pNext = &flags;
  ai.allocationSize = size;
  ai.memoryTypeIndex = type_;
  VkDeviceMemory m = VK_NULL_HANDLE;
  if (vkAllocateMemory(device_, &ai, nullptr, &m) != VK_SUCCESS) return false;
  blocks_.push_back(m);
  free_.emplace_back(size);
  bytes_ += size;
  return true;
}

std::optional<DeviceMemoryPool::Range> DeviceMemoryPool::take(const VkMemoryRequirements& req) {
  if (!(req.memoryTypeBits & (1u << type_))) return std::nullopt;
  const uint64_t alignment = std::max<uint64_t>(req.alignment, 1);
  std::lock_guard lock(mutex_);
  size_t best = blocks_.size();
  uint64_t least = 0;
  for (size_t b = 0; b < blocks_.size(); ++b)
    if (const auto left = free_[b].fit(req.size, alignment); left && (best == blocks_.size() || *left < least))
      best = b, least = *left;
  auto counted = [&] {
    taken_.fetch_add(1);
    in_use_ += req.size;
    most_in_use_ = std::max(most_in_use_, in_use_);
  };
  if (best < blocks_.size()) {
    const auto at = free_[best].take(req.size, alignment);
    counted();
    return Range{blocks_[best], uint32_t(best), *at, req.size};
  }
  // Grown by a block (a block's size, at most the pool's, at least the buffer's; else the buffer's) rather than
  // the buffer taking memory of its own: freed, that memory came back at the next tile as a driver allocation,
  // tile after tile (0.1 s each on two devices at once at 1B points; session 57).
  if (closed_) return std::nullopt;
  const uint64_t grow = std::max(req.size, std::min(block_bytes_, bytes_.load()));
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t before = bytes_.load();
  if (!add_block(grow) && !(grow > req.size && add_block(req.size))) return std::nullopt;
  spdlog::debug("device memory pool: grown by {:.0f} MB to {:.0f} MB in {:.1f} ms, for a buffer of {:.0f} MB",
                (bytes_.load() - before) / 1e6, bytes_.load() / 1e6,
                ms_since(t0),
                req.size / 1e6);
  const auto at = free_.back().take(req.size, alignment);
  if (!at) return std::nullopt;
  counted();
  return Range{blocks_.back(), uint32_t(blocks_.size() - 1), *at, req.size};
}

void DeviceMemoryPool::give(const Range& r) {
  std::lock_guard lock(mutex_);
  if (r.block < free_.size()) free_[r.block].give(r.offset, r.bytes);
  in_use_ -= std::min(in_use_, r.bytes);
}

uint64_t DeviceMemoryPool::free_bytes() {
  std::lock_guard lock(mutex_);
  uint64_t n = 0;
  for (const FreeRanges& f : free_) n += f.free_bytes();
  return n;
}

uint64_t DeviceMemoryPool::most_in_use() {
  std::lock_guard lock(mutex_);
  return most_in_use_;
}

bool DeviceMemoryPool::release_block() {
  std::lock_guard lock(mutex_);
  if (blocks_.empty() || in_use_ > 0) return false;
  closed_ = true;
  vkFreeMemory(device_, blocks_.back(), nullptr);
  blocks_.pop_back();
  free_.pop_back();
  return true;
}

void DeviceMemoryPool::free_blocks() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  if (blocks_.empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  for (VkDeviceMemory m : blocks_) vkFreeMemory(device_, m, nullptr);
  // Where the blocks hold much more than the buffers ever did, the rest is the best fit's waste, which the
  // driver makes and frees like the rest (~25 ms a GB; scripts/memory_probe.cpp).
  spdlog::debug("device memory pool: {:.0f} MB in {} block(s) freed in {:.1f} ms; at most {:.0f} MB of it in use",
                bytes_.load() / 1e6, blocks_.size(),
                ms_since(t0),
                most_in_use_ / 1e6);
  blocks_.clear();
  free_.clear();
}

}  // namespace cdtgpu::gpu
