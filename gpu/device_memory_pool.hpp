// Device memory made in a few large blocks before a run and handed out to its buffers (gpu/buffers' make). A
// run of 10^8 points makes ~35 device buffers, 32 GB, each when its stage begins; the driver took ~1 s for them
// on the H200 machine, between the GPU's stages. Made beside the start's staging (ContextOptions::
// device_pool_bytes), the blocks cost about as much, but while the input is read and prepared. Best fit over
// the blocks' free ranges, merged as buffers give them back (first fit left a tiles' pool of 33 GB so cut up that
// it grew to 63 GB for a 29 GB peak); where a buffer fits nowhere the pool grows by a
// block, and only where the device has no room for one does the buffer get memory of its own.
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

namespace cdtgpu::gpu {

struct Context;

// The bookkeeping of one block: free ranges by offset, best fit, merged with their neighbours when given back.
class FreeRanges {
 public:
  explicit FreeRanges(uint64_t size);
  // What the best fit for `bytes` at a multiple of `alignment` (a power of two) would leave of its range, or none.
  std::optional<uint64_t> fit(uint64_t bytes, uint64_t alignment) const;
  // The offset of that best fit (the range that `bytes` leaves least of; the lowest of equals), or none.
  std::optional<uint64_t> take(uint64_t bytes, uint64_t alignment);
  void give(uint64_t offset, uint64_t bytes);
  uint64_t free_bytes() const;

 private:
  std::map<uint64_t, uint64_t> free_;  // offset -> size
};

class DeviceMemoryPool {
 public:
  struct Range {
    VkDeviceMemory memory = VK_NULL_HANDLE;
    uint32_t block = 0;
    uint64_t offset = 0, bytes = 0;
  };
  // Blocks of up to `block_bytes` (the driver's largest allocation or less) until `bytes` are made, of memory
  // type `type`, with device addresses where `addressed`; fewer where the device runs out.
  DeviceMemoryPool(const Context& ctx, uint64_t bytes, uint64_t block_bytes, uint32_t type, bool addressed);
  ~DeviceMemoryPool() { free_blocks(); }
  DeviceMemoryPool(const DeviceMemoryPool&) = delete;
  DeviceMemoryPool& operator=(const DeviceMemoryPool&) = delete;

  // Memory for a buffer with these requirements, from the blocks or a block added for it (a block's size, at
  // most the pool's, at least the buffer's); none for another memory type, or where the device has no room.
  std::optional<Range> take(const VkMemoryRequirements& req);
  void give(const Range& r);
  // The blocks' memory back to the driver (before the device goes; buffers still out must not be used).
  void free_blocks();
  // One block back to the driver, the last, for a pool that no buffer uses any more: a caller frees the blocks
  // one at a time between other work's driver calls (gpu/tile_triangulator). False when none is left or a
  // buffer still uses the pool.
  bool release_block();
  uint64_t bytes() const { return bytes_.load(); }
  uint64_t free_bytes();
  uint64_t ranges_taken() const { return taken_; }  // how many buffers took memory here so far
  uint64_t most_in_use();                            // the most bytes its buffers held at once

 private:
  bool add_block(uint64_t size);  // mutex_ held (or in the constructor)
  VkDevice device_ = VK_NULL_HANDLE;
  uint32_t type_ = 0;
  uint64_t block_bytes_ = 0;
  bool addressed_ = false;
  bool closed_ = false;  // free_blocks() ran: no more blocks
  std::atomic<uint64_t> bytes_{0};  // grows under mutex_; read by bytes() without it
  std::atomic<uint64_t> taken_{0};
  uint64_t in_use_ = 0, most_in_use_ = 0;  // bytes of the ranges out, now and at most (mutex_): -v at the free
  std::mutex mutex_;
  std::vector<VkDeviceMemory> blocks_;
  std::vector<FreeRanges> free_;
};

}  // namespace cdtgpu::gpu
