// Device-local buffers and synchronous staging copies; see buffers.hpp.
#include "gpu/buffers.hpp"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <optional>
#include <utility>

#include "core/parallel.hpp"
#include "gpu/check.hpp"
#include "gpu/recorder.hpp"

namespace cdtgpu::gpu {
namespace {

std::atomic<uint64_t> memory_ns{0};

// Adds the time from its construction to its end to memory_ns.
constexpr VkDeviceSize kLoggedBytes = VkDeviceSize(64) << 20;

struct MemoryClock {
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  ~MemoryClock() {
    memory_ns += uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
  }
};

uint32_t memory_type(const Context& ctx, uint32_t type_bits, VkMemoryPropertyFlags want, VkMemoryPropertyFlags need) {
  for (int pass = 0; pass < 2; ++pass) {
    VkMemoryPropertyFlags flags = pass == 0 ? (want | need) : need;
    for (uint32_t i = 0; i < ctx.memory.memoryTypeCount; ++i)
      if ((type_bits & (1u << i)) && (ctx.memory.memoryTypes[i].propertyFlags & flags) == flags) return i;
  }
  throw DeviceError("no suitable Vulkan memory type on " + ctx.info.name);
}

// Raw buffer + memory; `host` makes it host-visible and coherent (staging); `addressed` gives it a device
// address.
VkBuffer new_buffer(const Context& ctx, VkDeviceSize bytes, bool host, bool addressed) {
  VkBufferCreateInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bi.size = bytes ? bytes : 4;
  bi.usage = host ? (VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT)
                  : (VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                     VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT);
  if (addressed) bi.usage |= VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT;
  // Shared by the compute and copy families: no ownership transfers between the two queues.
  const uint32_t families[] = {ctx.queue_family, ctx.copy_family};
  const bool shared = ctx.copy_queue && ctx.copy_family != ctx.queue_family;
  bi.sharingMode = shared ? VK_SHARING_MODE_CONCURRENT : VK_SHARING_MODE_EXCLUSIVE;
  bi.queueFamilyIndexCount = shared ? 2 : 0;
  bi.pQueueFamilyIndices = shared ? families : nullptr;
  VkBuffer buffer = VK_NULL_HANDLE;
  VK_CHECK(vkCreateBuffer(ctx.device, &bi, nullptr, &buffer));
  return buffer;
}

Buffer make(const Context& ctx, VkDeviceSize bytes, const std::string& name, bool host, bool addressed = false) {
  MemoryClock clock;
  Buffer b;
  b.device = ctx.device;
  b.size = bytes;
  b.name = name;
  b.buffer = new_buffer(ctx, bytes, host, addressed);
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device, b.buffer, &req);
  VkMemoryAllocateFlagsInfo flags{};
  flags.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO;
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  if (addressed) ai.pNext = &flags;
  ai.allocationSize = req.size;
  ai.memoryTypeIndex =
      host ? memory_type(ctx, req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_CACHED_BIT,
                         VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
           : memory_type(ctx, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  if (!host) {  // the context's cap (CDTGPU_DEVICE_MEMORY_LIMIT): refused as the device refuses what it lacks
    MemoryBudget& m = *ctx.memory_budget;
    const uint64_t after = m.used.fetch_add(req.size) + req.size;
    if (m.limit && after > m.limit) {
      m.used.fetch_sub(req.size);
      vkDestroyBuffer(ctx.device, b.buffer, nullptr);
      b.buffer = VK_NULL_HANDLE;
      throw TooLarge("out of device memory: buffer '" + name + "' of " + std::to_string(req.size) +
                         " bytes would bring the GPU backend to " + std::to_string(after) +
                         " bytes, over CDTGPU_DEVICE_MEMORY_LIMIT = " + std::to_string(m.limit) + " bytes",
                     double(after), double(m.limit));
    }
    b.budget = ctx.memory_budget;
    b.charged = req.size;
  }
  std::optional<DeviceMemoryPool::Range> pooled;
  const std::shared_ptr<DeviceMemoryPool> pool = host ? nullptr : ctx.memory_pool.load();
  if (pool) pooled = pool->take(req);
  if (pooled) {
    b.pool = pool;
    b.range = *pooled;
    VK_CHECK(vkBindBufferMemory(ctx.device, b.buffer, pooled->memory, pooled->offset));
  } else {
    VkResult r = vkAllocateMemory(ctx.device, &ai, nullptr, &b.memory);
    if (r != VK_SUCCESS)
      vk_fail(r, ("vkAllocateMemory for buffer '" + name + "' of " + std::to_string(bytes) + " bytes").c_str(),
              __FILE__, __LINE__);
    VK_CHECK(vkBindBufferMemory(ctx.device, b.buffer, b.memory, 0));
  }
  if (addressed) {
    VkBufferDeviceAddressInfo info{};
    info.sType = VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO;
    info.buffer = b.buffer;
    b.address = vkGetBufferDeviceAddress(ctx.device, &info);
  }
  if (bytes >= kLoggedBytes)  // -v: where the tiles' allocation time goes (issue 29)
    spdlog::debug("{} buffer '{}': {:.0f} MB {} in {:.1f} ms", host ? "host" : "device", name, bytes / 1e6,
                  pooled ? "taken from the pool" : "allocated",
                  std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - clock.t0).count());
  return b;
}

// Gives a buffer's memory back: to the pool it came from, or to the driver.
void free_memory(Buffer& b) {
  if (b.pool) {
    b.pool->give(b.range);
    b.pool.reset();
  } else if (b.memory) {
    vkFreeMemory(b.device, b.memory, nullptr);
  }
  b.memory = VK_NULL_HANDLE;
}

void full_barrier(VkCommandBuffer cmd) {
  VkMemoryBarrier mb{};
  mb.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  mb.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT | VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT | VK_PIPELINE_STAGE_HOST_BIT,
                       0, 1, &mb, 0, nullptr, 0, nullptr);
}

// Records `record` into a fresh command buffer, submits it on the context's compute queue (or its copy queue,
// where it has one) and waits.
void run_once(const Context& ctx, const std::function<void(VkCommandBuffer)>& record, Queue on = Queue::compute) {
  const bool aside = on == Queue::copy && ctx.copy_queue;
  const VkQueue queue = aside ? ctx.copy_queue : ctx.queue;
  const VkCommandPool pool = aside ? ctx.copy_pool : ctx.pool;
  VkCommandBufferAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  ai.commandPool = pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  VK_CHECK(vkAllocateCommandBuffers(ctx.device, &ai, &cmd));
  VkFence fence = VK_NULL_HANDLE;
  try {
    VkCommandBufferBeginInfo bi{};
    bi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd, &bi));
    full_barrier(cmd);  // orders against earlier submissions on this queue
    record(cmd);
    full_barrier(cmd);  // and makes the result visible to the host and to later submissions
    VK_CHECK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fi{};
    fi.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
    VK_CHECK(vkCreateFence(ctx.device, &fi, nullptr, &fence));
    submit_and_wait(ctx.device, queue, cmd, fence);
  } catch (...) {
    if (fence) vkDestroyFence(ctx.device, fence, nullptr);
    vkFreeCommandBuffers(ctx.device, pool, 1, &cmd);
    throw;
  }
  vkDestroyFence(ctx.device, fence, nullptr);
  vkFreeCommandBuffers(ctx.device, pool, 1, &cmd);
}

// One copy between buffers on the device, synchronously.
void copy_region(const Context& ctx, VkBuffer src, VkDeviceSize src_offset, VkBuffer dst, VkDeviceSize dst_offset,
                 VkDeviceSize bytes, Queue on = Queue::compute) {
  run_once(
      ctx,
      [&](VkCommandBuffer cmd) {
        VkBufferCopy region{src_offset, dst_offset, bytes};
        vkCmdCopyBuffer(cmd, src, dst, 1, &region);
      },
      on);
}

void check_range(const Buffer& b, VkDeviceSize bytes, VkDeviceSize offset, const char* what) {
  if (offset + bytes > b.size)
    throw DeviceError(std::string(what) + " of " + std::to_string(bytes) + " bytes at offset " +
                      std::to_string(offset) + " past the end of buffer '" + b.name + "' (" + std::to_string(b.size) +
                      " bytes)");
}

}  // namespace

Buffer::Buffer(Buffer&& o) noexcept { *this = std::move(o); }

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this == &o) return *this;
  if (buffer) vkDestroyBuffer(device, buffer, nullptr);
  free_memory(*this);
  if (budget) budget->used.fetch_sub(charged);
  device = o.device;
  budget = std::move(o.budget);
  charged = std::exchange(o.charged, 0);
  pool = std::move(o.pool);
  range = o.range;
  buffer = std::exchange(o.buffer, VK_NULL_HANDLE);
  memory = std::exchange(o.memory, VK_NULL_HANDLE);
  size = std::exchange(o.size, 0);
  address = std::exchange(o.address, 0);
  name = std::move(o.name);
  return *this;
}

double memory_ms() { return double(memory_ns.load()) * 1e-6; }

std::shared_ptr<DeviceMemoryPool> make_device_pool(const Context& ctx, uint64_t bytes) {
  VkBuffer probe = new_buffer(ctx, 4, false, ctx.info.buffer_address);  // the memory type make() would pick
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device, probe, &req);
  vkDestroyBuffer(ctx.device, probe, nullptr);
  const uint32_t type = memory_type(ctx, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  VkPhysicalDeviceMaintenance3Properties m3{};
  m3.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES;
  VkPhysicalDeviceProperties2 p2{};
  p2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
  p2.pNext = &m3;
  vkGetPhysicalDeviceProperties2(ctx.physical, &p2);
  // Blocks of 8 GiB at most: each holds a few of the largest buffers (3-4 GB at 10^8 points). At most three
  // quarters of the device's memory: the estimate of the input may be high.
  const uint64_t block = std::min<uint64_t>(uint64_t(8) << 30, m3.maxMemoryAllocationSize);
  uint64_t heap = 0;
  for (size_t h = 0; h < ctx.info.heap_sizes.size(); ++h)
    if (ctx.info.heap_device_local[h]) heap = std::max(heap, ctx.info.heap_sizes[h]);
  return std::make_shared<DeviceMemoryPool>(ctx, std::min(bytes, heap / 4 * 3), block, type,
                                            ctx.info.buffer_address);
}

Buffer::~Buffer() {
  MemoryClock clock;
  const bool logged = (memory || pool) && size >= kLoggedBytes;
  if (buffer) vkDestroyBuffer(device, buffer, nullptr);
  free_memory(*this);
  if (budget) budget->used.fetch_sub(charged);
  if (logged)
    spdlog::debug("buffer '{}': {:.0f} MB freed in {:.1f} ms", name, size / 1e6,
                  std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - clock.t0).count());
}

void require_storage_range(const Context& ctx, VkDeviceSize bytes, const std::string& name) {
  if (bytes > ctx.info.max_storage_buffer_range)
    throw TooLarge("buffer '" + name + "' needs " + std::to_string(bytes) + " bytes, more than the device limit maxStorageBufferRange = " +
                       std::to_string(ctx.info.max_storage_buffer_range) + " bytes (" +
                       std::to_string(ctx.info.max_storage_buffer_range >> 20) + " MiB) of " + ctx.info.name +
                       "; use a smaller input or a device with a larger limit",
                   double(bytes), double(ctx.info.max_storage_buffer_range));
}

Buffer create_buffer(const Context& ctx, VkDeviceSize bytes, const std::string& name) {
  require_storage_range(ctx, bytes, name);  // every buffer is bound whole as one storage-buffer descriptor
  return make(ctx, bytes, name, false);
}

Buffer create_addressed_buffer(const Context& ctx, VkDeviceSize bytes, const std::string& name) {
  return make(ctx, bytes, name, false, true);
}

namespace {

// One host-visible buffer per context, grown to the largest copy so far.
HostStaging& staging_of(const Context& ctx, VkDeviceSize bytes) {
  if (!ctx.staging) ctx.staging = std::make_shared<HostStaging>();
  HostStaging& s = *static_cast<HostStaging*>(ctx.staging.get());
  s.fit(ctx, bytes);
  return s;
}

}  // namespace

HostStaging::~HostStaging() {
  if (mapped) vkUnmapMemory(buffer.device, buffer.memory);
}

void HostStaging::fit(const Context& ctx, VkDeviceSize bytes) {
  if (mapped && buffer.size >= bytes) return;
  // Regrown by an eighth at least: pinned memory costs ~0.3 ms per MB, and tiles' copies differ by a few %.
  const VkDeviceSize size = mapped ? std::max(bytes, buffer.size + buffer.size / 8) : bytes;
  if (mapped) vkUnmapMemory(buffer.device, buffer.memory);
  mapped = nullptr;
  buffer = Buffer();
  buffer = make(ctx, size, "staging", true);
  VK_CHECK(vkMapMemory(ctx.device, buffer.memory, 0, VK_WHOLE_SIZE, 0, &mapped));
}

StagingLent::StagingLent(const Context& ctx, HostStaging& staging)
    : ctx_(ctx), own_(std::exchange(ctx.staging, std::shared_ptr<void>(std::shared_ptr<void>(), &staging))) {}

StagingLent::~StagingLent() { ctx_.staging = std::move(own_); }

void copy_from_staging(const Context& ctx, const HostStaging& staging, const Buffer& dst, VkDeviceSize bytes,
                       Queue on, VkDeviceSize staging_offset) {
  check_range(dst, bytes, 0, "copy from staging");
  check_range(staging.buffer, bytes, staging_offset, "copy from staging");
  if (bytes) copy_region(ctx, staging.buffer.buffer, staging_offset, dst.buffer, 0, bytes, on);
}

void copy_to_staging(const Context& ctx, const Buffer& src, const HostStaging& staging, VkDeviceSize bytes,
                     Queue on) {
  check_range(src, bytes, 0, "copy to staging");
  if (bytes) copy_region(ctx, src.buffer, 0, staging.buffer.buffer, 0, bytes, on);
}

void reserve_staging(const Context& ctx, VkDeviceSize bytes) {
  if (bytes) staging_of(ctx, bytes);
}

void upload_with(const Context& ctx, const Buffer& dst, VkDeviceSize bytes, const std::function<void(void*)>& write,
                 VkDeviceSize offset) {
  check_range(dst, bytes, offset, "upload");
  if (!bytes) return;
  HostStaging& staging = staging_of(ctx, bytes);
  write(staging.mapped);
  copy_region(ctx, staging.buffer.buffer, 0, dst.buffer, offset, bytes);
}

void download(const Context& ctx, const Buffer& src, void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  check_range(src, bytes, offset, "download");
  if (!bytes) return;
  HostStaging& staging = staging_of(ctx, bytes);
  copy_region(ctx, src.buffer, offset, staging.buffer.buffer, 0, bytes);
  // Large copies on all cores: the destination is usually fresh memory, and its page faults and the copy
  // itself took ~30 ms for a 2M-point triangulation's 48 MB on one core.
  copy_on_all_cores(static_cast<const char*>(staging.mapped), bytes, static_cast<char*>(data));
}

void upload(const Context& ctx, const Buffer& dst, const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  upload_with(
      ctx, dst, bytes,
      [&](void* mapped) { copy_on_all_cores(static_cast<const char*>(data), bytes, static_cast<char*>(mapped)); },
      offset);
}

Buffer& BufferCache::fit(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label,
                         bool addressed) {
  Buffer& b = buffers_[key];
  if (!b.buffer || b.size < bytes) {
    const VkDeviceSize want = b.buffer && grow_by > 0 ? std::max(bytes, b.size + VkDeviceSize(double(b.size) * grow_by))
                              : b.buffer                ? bytes
                                                        : bytes + VkDeviceSize(double(bytes) * first_room);
    b = Buffer();  // the old one goes first: a lower peak
    b = addressed ? create_addressed_buffer(ctx, want, label)
                  : create_buffer(ctx, std::min(want, std::max(bytes, ctx.info.max_storage_buffer_range)), label);
  }
  return b;
}

const Buffer& BufferCache::get(const Context& ctx, const std::string& key, VkDeviceSize bytes,
                               const std::string& label) {
  return fit(ctx, key, bytes, label.empty() ? key : label, false);
}

Buffer BufferCache::take(const Context& ctx, const std::string& key, VkDeviceSize bytes, const std::string& label) {
  get(ctx, key, bytes, label);
  return std::move(buffers_[key]);
}

Buffer BufferCache::take_addressed(const Context& ctx, const std::string& key, VkDeviceSize bytes,
                                   const std::string& label) {
  return std::move(fit(ctx, key, bytes, label, true));
}

void BufferCache::give(const std::string& key, Buffer b) {
  if (b.buffer) buffers_[key] = std::move(b);
}

uint64_t BufferCache::bytes() const {
  uint64_t total = 0;
  for (const auto& [key, b] : buffers_) total += b.size;
  return total;
}

void fill(const Context& ctx, const Buffer& dst, uint32_t value) {
  run_once(ctx, [&](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, dst.buffer, 0, VK_WHOLE_SIZE, value); });
}

}  // namespace cdtgpu::gpu
