// Records a sequence of compute dispatches (and fills/copies) into ONE command buffer, with a full
// compute/transfer -> compute/transfer/indirect memory barrier between consecutive commands, then submits and
// waits. Scratch buffers made with temp() live until the next submit() returns (small ones then go back to the
// context's pool for the next recording).
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <deque>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"

namespace cdtgpu::gpu {

// A storage-buffer binding: a whole buffer or a range of it (offset must respect minStorageBufferOffsetAlignment).
// A buffer made by create_addressed_buffer is bound by its address (plus the offset): the recorder writes it
// into a small buffer of its own and binds that, and the pass must declare the binding so (Pass::addressed).
struct Binding {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceSize offset = 0;
  VkDeviceSize range = VK_WHOLE_SIZE;
  VkDeviceAddress address = 0;
  Binding(const Buffer& b) : buffer(b.buffer), address(b.address) {}  // NOLINT: implicit on purpose, {a, b, c} reads well
  Binding(const Buffer& b, VkDeviceSize offset, VkDeviceSize range)
      : buffer(b.buffer), offset(offset), range(range), address(b.address ? b.address + offset : 0) {}
};

// The context's pooled temps (the small scratch buffers recordings reuse) freed: for a device whose work is
// done, so that its memory pool can go (gpu/tile_triangulator). Nothing may be recording on it.
void drop_temps(const Context& ctx);

// This thread's submits so far (Recorder::submit): their count and the ms from each submit to its fence, for
// the -v lines that split a device's held time into host work and waits.
struct SubmitTally {
  uint64_t submits = 0;
  double wait_ms = 0;
};
SubmitTally submit_tally();
// Submits `cmd` to `queue` and waits for `fence`, counted in this thread's tally.
void submit_and_wait(VkDevice device, VkQueue queue, VkCommandBuffer cmd, VkFence fence);

class Recorder {
 public:
  explicit Recorder(const Context& ctx);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Dispatch with explicit group counts; push may be null when pass.push_size is 0.
  void dispatch(const Pass& pass, std::initializer_list<Binding> bindings, const void* push, uint32_t gx,
                uint32_t gy = 1, uint32_t gz = 1);
  template <class P>
  void dispatch(const Pass& pass, std::initializer_list<Binding> bindings, const P& push, uint32_t gx,
                uint32_t gy = 1, uint32_t gz = 1) {
    check_push(pass, sizeof(P));
    dispatch(pass, bindings, static_cast<const void*>(&push), gx, gy, gz);
  }
  // `groups` workgroups in 1D, split over x and y when above maxComputeWorkGroupCount[0]; the shader gets its
  // index from linear_group_id() and must skip work past its element count (the split may add a few groups).
  template <class P>
  void dispatch_groups(const Pass& pass, std::initializer_list<Binding> bindings, const P& push, uint64_t groups) {
    check_push(pass, sizeof(P));
    dispatch_groups_raw(pass, bindings, &push, groups);
  }
  void dispatch_groups_raw(const Pass& pass, std::initializer_list<Binding> bindings, const void* push,
                           uint64_t groups);
  // Group counts read from `args` (VkDispatchIndirectCommand: three uint32) at `offset`.
  void dispatch_indirect(const Pass& pass, std::initializer_list<Binding> bindings, const void* push,
                         const Buffer& args, VkDeviceSize offset = 0);

  void fill(const Buffer& dst, uint32_t value);
  void copy(const Buffer& src, const Buffer& dst, VkDeviceSize bytes, VkDeviceSize src_offset = 0,
            VkDeviceSize dst_offset = 0);
  // Writes `bytes` of `data` (a multiple of 4, at most 65536) at `offset` of dst from the command buffer itself.
  void update(const Buffer& dst, VkDeviceSize offset, const void* data, VkDeviceSize bytes);
  // A scratch buffer owned by the recorder until submit() returns.
  const Buffer& temp(VkDeviceSize bytes, const std::string& name = "temp");

  // Ends the command buffer, submits it, waits, frees the scratch buffers; the recorder can then record again.
  void submit();

  VkCommandBuffer cmd() const { return cmd_; }
  const Context& context() const { return ctx_; }
  // Called before every command: inserts the memory barrier when something was recorded before.
  void barrier();

 private:
  void begin();
  void check_push(const Pass& pass, size_t bytes) const;
  void bind(const Pass& pass, std::initializer_list<Binding> bindings, const void* push);

  const Context& ctx_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  bool recording_ = false;
  bool any_ = false;  // a command has been recorded since begin
  std::deque<Buffer> temps_;
  // Addresses written for address bindings in this recording: one 8-byte cell each, in cells_.
  const Buffer* cells_ = nullptr;
  std::vector<std::pair<VkDeviceAddress, VkDeviceSize>> cell_of_;
  VkDeviceSize address_cell(VkDeviceAddress address);
};

}  // namespace cdtgpu::gpu
