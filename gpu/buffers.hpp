// Device-local storage buffers, staging upload/download and fill.
//
// Size policy: a buffer is bound whole as one storage-buffer descriptor, so a buffer larger than the device's
// maxStorageBufferRange (128 MiB on lavapipe, 4 GiB on NVIDIA) is refused by create_buffer with a DeviceError
// naming the limit. Callers split their data or run on a device with a larger range. The triangulation's
// verts and nbrs are the exception: create_addressed_buffer makes buffers that shaders reach through their
// device address (shaders/tri_refs.glsl), which has no range limit.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "core/touched.hpp"
#include "gpu/context.hpp"
#include "gpu/device_memory_pool.hpp"

namespace cdtgpu::gpu {

// A device-local buffer usable as storage buffer, transfer source/destination and indirect-dispatch argument.
// Move-only; `size` is what was asked for (0 allowed: a 4-byte buffer is made, since Vulkan forbids empty ones).
struct Buffer {
  VkDevice device = VK_NULL_HANDLE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
  VkDeviceAddress address = 0;  // create_addressed_buffer: what its bindings pass (gpu/recorder.hpp); else 0
  std::string name;
  std::shared_ptr<MemoryBudget> budget;  // device-local buffers: the context's budget, given back when freed
  VkDeviceSize charged = 0;
  std::shared_ptr<DeviceMemoryPool> pool;      // memory taken from the context's pool (then `memory` is not its own)
  DeviceMemoryPool::Range range;

  Buffer() = default;
  Buffer(Buffer&& o) noexcept;
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer();
};

// Throws TooLarge when bytes > maxStorageBufferRange (message names the buffer, its size and the limit).
void require_storage_range(const Context& ctx, VkDeviceSize bytes, const std::string& name);
// Throws DeviceError when bytes > maxStorageBufferRange (message names the buffer, its size and the limit).
Buffer create_buffer(const Context& ctx, VkDeviceSize bytes, const std::string& name = "buffer");
// A buffer that every pass binds by its device address (Binding, Recorder::bind): no range limit.
Buffer create_addressed_buffer(const Context& ctx, VkDeviceSize bytes, const std::string& name);

// Device memory for the context's buffers to take first (Context::memory_pool), `bytes` in blocks the driver
// allows, of the memory type and with the device addresses that device buffers need.
std::shared_ptr<DeviceMemoryPool> make_device_pool(const Context& ctx, uint64_t bytes);

// Milliseconds the process has spent allocating and freeing buffer memory (device and staging), all threads.
double memory_ms();

// Synchronous copies through a host-visible staging buffer (each waits for the queue to finish).
// A host-visible buffer, mapped for its whole life: the context's own (upload, download) or one a caller keeps
// for copies it makes without holding the device (a GPU tile's points and triangles, gpu/tile_triangulator).
struct HostStaging {
  Buffer buffer;
  void* mapped = nullptr;
  HostStaging() = default;
  HostStaging(const HostStaging&) = delete;
  HostStaging& operator=(const HostStaging&) = delete;
  ~HostStaging();
  // At least `bytes` long (regrown by an eighth at least; the old contents are lost).
  void fit(const Context& ctx, VkDeviceSize bytes);
};
// upload() and download() on `ctx` go through `staging` instead of the context's own buffer while this lives
// (a GPU tile's slot, lent to the calls made in it; gpu/cdt_pipeline, gpu/tile_triangulator). The caller holds
// the device: nothing else copies on it meanwhile.
class StagingLent {
 public:
  StagingLent(const Context& ctx, HostStaging& staging);
  ~StagingLent();
  StagingLent(const StagingLent&) = delete;
  StagingLent& operator=(const StagingLent&) = delete;

 private:
  const Context& ctx_;
  std::shared_ptr<void> own_;
};
// Where a copy runs: the compute queue (the caller holds the device), or the context's copy queue beside it
// (Context::copy_queue; the compute queue where there is none). Callers on the copy queue take turns.
enum class Queue { compute, copy };
// The device's copies between a staging buffer (from its start, or from staging_offset) and a device buffer,
// synchronously.
void copy_from_staging(const Context& ctx, const HostStaging& staging, const Buffer& dst, VkDeviceSize bytes,
                       Queue on = Queue::compute, VkDeviceSize staging_offset = 0);
void copy_to_staging(const Context& ctx, const Buffer& src, const HostStaging& staging, VkDeviceSize bytes,
                     Queue on = Queue::compute);

void upload(const Context& ctx, const Buffer& dst, const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
void download(const Context& ctx, const Buffer& src, void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
// Grows the staging buffer that upload() and download() share to at least `bytes` now: pinned host memory costs
// about 0.3 ms per MB to allocate, which a caller can pay on another thread ahead of the copies.
void reserve_staging(const Context& ctx, VkDeviceSize bytes);
// upload() with the caller writing the mapped staging memory itself: no host copy of the data in between.
// Large fresh host vectors cost a page fault per 4 KiB (tens of ms per 100 MB), more than the copy.
void upload_with(const Context& ctx, const Buffer& dst, VkDeviceSize bytes, const std::function<void(void*)>& write,
                 VkDeviceSize offset = 0);
// Device buffers kept between calls by name, each grown when a call needs more: allocation costs more than the
// work on a fast GPU (about 35 us per MiB on the lent H100 machine, docs/gpu.md).
// Stages that run one after another can share one cache by asking for the same keys (GpuCdt does: the Delaunay
// build's scratch becomes the constraint inserter's), so what stays allocated is the largest stage's need.
class BufferCache {
 public:
  // The buffer under `key`, at least `bytes` long (created or regrown as `label`, default the key).
  const Buffer& get(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label = "");
  // The same, taken out of the cache for a caller that holds buffers by value; give() puts it back.
  Buffer take(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label = "");
  // take() of a buffer made by create_addressed_buffer (keys of their own: a key holds one kind).
  Buffer take_addressed(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label);
  void give(const std::string& key, Buffer b);
  // Device bytes the cache holds.
  uint64_t bytes() const;
  bool holds(const std::string& key) const { return buffers_.count(key) > 0; }
  // Frees every buffer.
  void clear() { buffers_.clear(); }
  // A buffer regrown gets this share more than the old one if that is more than asked: tiles come in sizes a
  // few percent apart, and each regrowth reallocated every buffer of the tile (5.2 s of 43.7 at 1B points).
  // 0 (single runs): exactly what is asked, the lower peak.
  double grow_by = 0;
  // A buffer made for the first time gets this share more than asked: the tiles after the first are a few
  // points larger as often as not, and each such regrowth reallocated all of the tile's buffers (the second of
  // four 80M-point tiles: 25 GB again, 1.7 s of its device call against 0.8 for the third).
  double first_room = 0;

 private:
  // The buffer under `key`, made (or regrown, by grow_by) to hold `bytes`.
  Buffer& fit(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label, bool addressed);
  std::map<std::string, Buffer> buffers_;
};

// Shared scratch keys by shape (n = points, slots = triangle slots): the stages of one triangulation ask for
// these, so a later stage reuses an earlier one's buffers. Every user initialises what it reads.
inline constexpr const char* kPoints4[] = {"points x4 a", "points x4 b", "points x4 c", "points x4 d"};
inline constexpr const char* kPoints16[] = {"points x16"};
inline constexpr const char* kSlots4[] = {"slots x4 a", "slots x4 b", "slots x4 c", "slots x4 d", "slots x4 e"};
inline constexpr const char* kSlots8[] = {"slots x8 a", "slots x8 b"};
inline constexpr const char* kSlots12[] = {"slots x12 a", "slots x12 b"};

// Fills the whole buffer with a 32-bit pattern, synchronously.
void fill(const Context& ctx, const Buffer& dst, uint32_t value);

// Creates a buffer holding `data`.
template <class T>
Buffer upload_new(const Context& ctx, std::span<const T> data, const std::string& name = "buffer") {
  Buffer b = create_buffer(ctx, data.size_bytes(), name);
  if (!data.empty()) upload(ctx, b, data.data(), data.size_bytes());
  return b;
}
template <class T>
Buffer upload_new(const Context& ctx, const std::vector<T>& data, const std::string& name = "buffer") {
  return upload_new(ctx, std::span<const T>(data), name);
}
// Reads the first `count` elements of `src`.
// The same into a RawVector: the download's copy, on all cores, is the only write (no zeroing first).
template <class T>
RawVector<T> download_raw(const Context& ctx, const Buffer& src, size_t count) {
  RawVector<T> out;
  resize_unwritten(out, count);
  if (count) download(ctx, src, out.data(), count * sizeof(T));
  return out;
}

template <class T>
std::vector<T> download_vector(const Context& ctx, const Buffer& src, size_t count) {
  std::vector<T> out(count);
  if (count) download(ctx, src, out.data(), count * sizeof(T));
  return out;
}

}  // namespace cdtgpu::gpu
