// One command buffer of dispatches with barriers between them; see recorder.hpp.
#include "gpu/recorder.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <memory>
#include <vector>

#include "gpu/check.hpp"

namespace cdtgpu::gpu {

namespace {

// Temps up to this size come from the context's pool (sized to powers of two); larger ones (sort scratch of n
// keys) are allocated and freed per recording, so they do not stay on the device between calls.
constexpr VkDeviceSize kPooledTempBytes = VkDeviceSize(1) << 20;

struct TempPool {
  std::vector<Buffer> free;
};

TempPool& pool_of(const Context& ctx) {
  if (!ctx.temp_pool) ctx.temp_pool = std::make_shared<TempPool>();
  return *static_cast<TempPool*>(ctx.temp_pool.get());
}

thread_local SubmitTally tally;

}  // namespace

SubmitTally submit_tally() { return tally; }

void submit_and_wait(VkDevice device, VkQueue queue, VkCommandBuffer cmd, VkFence fence) {
  VkSubmitInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  const auto t = std::chrono::steady_clock::now();
  VK_CHECK(vkQueueSubmit(queue, 1, &si, fence));
  VK_CHECK(vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX));
  ++tally.submits;
  tally.wait_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

void drop_temps(const Context& ctx) {
  if (ctx.temp_pool) pool_of(ctx).free.clear();
}

Recorder::Recorder(const Context& ctx) : ctx_(ctx) {
  VkCommandBufferAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  ai.commandPool = ctx.pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VK_CHECK(vkAllocateCommandBuffers(ctx.device, &ai, &cmd_));
  VkFenceCreateInfo fi{};
  fi.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  VkResult r = vkCreateFence(ctx.device, &fi, nullptr, &fence_);
  if (r != VK_SUCCESS) {
    vkFreeCommandBuffers(ctx.device, ctx.pool, 1, &cmd_);
    vk_fail(r, "vkCreateFence", __FILE__, __LINE__);
  }
}

Recorder::~Recorder() {
  // A recording that was never submitted is simply dropped; a submitted one has been waited for.
  if (recording_) vkEndCommandBuffer(cmd_);
  vkDestroyFence(ctx_.device, fence_, nullptr);
  vkFreeCommandBuffers(ctx_.device, ctx_.pool, 1, &cmd_);
}

void Recorder::begin() {
  if (recording_) return;
  VK_CHECK(vkResetCommandBuffer(cmd_, 0));
  VkCommandBufferBeginInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(cmd_, &bi));
  recording_ = true;
  any_ = false;
}

void Recorder::barrier() {
  begin();
  // Also before the first command: orders against earlier submissions on the queue (uploads, other recorders).
  VkMemoryBarrier mb{};
  mb.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                     VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_INDIRECT_COMMAND_READ_BIT;
  const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  vkCmdPipelineBarrier(cmd_, stages, stages | VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT, 0, 1, &mb, 0, nullptr, 0, nullptr);
  any_ = true;
}

void Recorder::check_push(const Pass& pass, size_t bytes) const {
  if (bytes != pass.push_size)
    throw DeviceError("pass '" + pass.name + "' declares " + std::to_string(pass.push_size) +
                      " push-constant bytes, given " + std::to_string(bytes));
}

void Recorder::bind(const Pass& pass, std::initializer_list<Binding> bindings, const void* push) {
  if (bindings.size() != pass.buffers)
    throw DeviceError("pass '" + pass.name + "' declares " + std::to_string(pass.buffers) + " buffers, given " +
                      std::to_string(bindings.size()));
  if (pass.push_size && !push) throw DeviceError("pass '" + pass.name + "' needs push constants");
  std::vector<VkDescriptorBufferInfo> infos;
  infos.reserve(bindings.size());
  for (const Binding& b : bindings) {
    const uint32_t i = uint32_t(infos.size());
    const bool wants = (pass.addressed >> i) & 1u;
    if (wants != (b.address != 0))
      throw DeviceError("pass '" + pass.name + "' binding " + std::to_string(i) +
                        (wants ? " takes a buffer address, given a plain buffer"
                               : " takes a plain buffer, given one bound by its address"));
    if (b.address) {
      const VkDeviceSize at = address_cell(b.address);
      infos.push_back({cells_->buffer, at, 8});
    } else {
      infos.push_back({b.buffer, b.offset, b.range});
    }
  }
  barrier();  // also orders the cells' writes before the dispatch
  vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pass.handle());
  std::vector<VkWriteDescriptorSet> writes;
  for (uint32_t i = 0; i < infos.size(); ++i) {
    VkWriteDescriptorSet w{};
    w.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
    w.dstBinding = i;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    w.pBufferInfo = &infos[i];
    writes.push_back(w);
  }
  if (!writes.empty())
    ctx_.cmd_push_descriptor_set(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pass.layout, 0,
                                 static_cast<uint32_t>(writes.size()), writes.data());
  if (pass.push_size) vkCmdPushConstants(cmd_, pass.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, pass.push_size, push);
}

// Cells of one recording: written inline (vkCmdUpdateBuffer) before their first use, read-only afterwards.
VkDeviceSize Recorder::address_cell(VkDeviceAddress address) {
  for (const auto& [a, at] : cell_of_)
    if (a == address) return at;
  const VkDeviceSize stride = std::max<VkDeviceSize>(8, ctx_.props.limits.minStorageBufferOffsetAlignment);
  const VkDeviceSize at = VkDeviceSize(cell_of_.size()) * stride;
  if (!cells_ || at + 8 > cells_->size) {
    // A fresh block: the one before keeps its cells until submit.
    cells_ = &temp(4096, "address cells");
    cell_of_.clear();
    return address_cell(address);
  }
  begin();
  vkCmdUpdateBuffer(cmd_, cells_->buffer, at, 8, &address);
  any_ = true;
  cell_of_.push_back({address, at});
  return at;
}

void Recorder::dispatch(const Pass& pass, std::initializer_list<Binding> bindings, const void* push, uint32_t gx,
                        uint32_t gy, uint32_t gz) {
  if (!gx || !gy || !gz) return;
  bind(pass, bindings, push);
  vkCmdDispatch(cmd_, gx, gy, gz);
}

void Recorder::dispatch_groups_raw(const Pass& pass, std::initializer_list<Binding> bindings, const void* push,
                                   uint64_t groups) {
  if (!groups) return;
  uint64_t max_x = ctx_.props.limits.maxComputeWorkGroupCount[0];
  uint64_t x = std::min(groups, max_x);
  uint64_t y = (groups + x - 1) / x;
  if (y > ctx_.props.limits.maxComputeWorkGroupCount[1])
    throw DeviceError("pass '" + pass.name + "': " + std::to_string(groups) + " workgroups exceed the device limits");
  bind(pass, bindings, push);
  vkCmdDispatch(cmd_, static_cast<uint32_t>(x), static_cast<uint32_t>(y), 1);
}

void Recorder::dispatch_indirect(const Pass& pass, std::initializer_list<Binding> bindings, const void* push,
                                 const Buffer& args, VkDeviceSize offset) {
  bind(pass, bindings, push);
  vkCmdDispatchIndirect(cmd_, args.buffer, offset);
}

void Recorder::fill(const Buffer& dst, uint32_t value) {
  barrier();
  vkCmdFillBuffer(cmd_, dst.buffer, 0, VK_WHOLE_SIZE, value);
}

void Recorder::copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize src_offset,
                    VkDeviceSize dst_offset) {
  if (!bytes) return;
  if (src_offset + bytes > src.size || dst_offset + bytes > dst.size)
    throw DeviceError("copy of " + std::to_string(bytes) + " bytes from '" + src.name + "' to '" + dst.name +
                      "' out of range");
  barrier();
  VkBufferCopy region{src_offset, dst_offset, bytes};
  vkCmdCopyBuffer(cmd_, src.buffer, dst.buffer, 1, &region);
}

void Recorder::update(const Buffer& dst, VkDeviceSize offset, const void* data, VkDeviceSize bytes) {
  if (!bytes) return;
  if (bytes % 4 || offset % 4 || bytes > 65536 || offset + bytes > dst.size)
    throw DeviceError("update of " + std::to_string(bytes) + " bytes at " + std::to_string(offset) + " of '" +
                      dst.name + "': not a multiple of 4, over 65536 bytes or out of range");
  barrier();
  vkCmdUpdateBuffer(cmd_, dst.buffer, offset, bytes, data);
}

const Buffer& Recorder::temp(VkDeviceSize bytes, const std::string& name) {
  if (bytes > kPooledTempBytes) {
    temps_.push_back(create_buffer(ctx_, bytes, name));
    return temps_.back();
  }
  std::vector<Buffer>& free = pool_of(ctx_).free;
  auto best = free.end();
  for (auto it = free.begin(); it != free.end(); ++it)
    if (it->size >= bytes && (best == free.end() || it->size < best->size)) best = it;
  if (best == free.end()) {
    temps_.push_back(create_buffer(ctx_, std::bit_ceil(std::max<VkDeviceSize>(bytes, 4096)), "pooled temp"));
  } else {
    temps_.push_back(std::move(*best));
    free.erase(best);
  }
  return temps_.back();
}

void Recorder::submit() {
  begin();
  // Results visible to the host (downloads map staging memory) and to later submissions.
  VkMemoryBarrier mb{};
  mb.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT | VK_ACCESS_MEMORY_READ_BIT | VK_ACCESS_MEMORY_WRITE_BIT;
  vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_HOST_BIT | VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 1, &mb, 0, nullptr, 0,
                       nullptr);
  recording_ = false;
  VK_CHECK(vkEndCommandBuffer(cmd_));
  VK_CHECK(vkResetFences(ctx_.device, 1, &fence_));
  submit_and_wait(ctx_.device, ctx_.queue, cmd_, fence_);
  // The work is done: small temps go back to the pool, large ones are freed.
  for (Buffer& b : temps_)
    if (b.size <= kPooledTempBytes) pool_of(ctx_).free.push_back(std::move(b));
  temps_.clear();
  cells_ = nullptr;
  cell_of_.clear();
}

}  // namespace cdtgpu::gpu
