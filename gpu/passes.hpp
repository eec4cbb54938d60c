// A compute pass: a pipeline built from SPIR-V embedded at build time (every shaders/*.comp, looked up by file
// name without extension). Its descriptor-set layout (N storage buffers at bindings 0..N-1, bound with push
// descriptors) and pipeline layout (one push-constant range) are derived from the declared binding count and
// push-constant size: adding a pass is a .comp file plus one create_pass line.
//
// Usage (struct FooPush and FOO_WG live in shaders/layout.h, shared with the shader):
//
//   gpu::ContextOptions options;  options.validation = true;
//   gpu::Context ctx = gpu::create_context(options);
//   gpu::Pass foo = gpu::create_pass(ctx, {"foo", 2, sizeof(FooPush)});  // shaders/foo.comp, bindings 0,1
//   gpu::Buffer in = gpu::upload_new(ctx, values, "in");
//   gpu::Buffer out = gpu::create_buffer(ctx, values.size() * sizeof(uint32_t), "out");
//   gpu::Recorder rec(ctx);
//   FooPush push{uint32_t(values.size())};
//   rec.dispatch_groups(foo, {in, out}, push, (push.n + FOO_WG - 1) / FOO_WG);  // barriers are automatic
//   rec.submit();                                                              // submit and wait
//   std::vector<uint32_t> result = gpu::download_vector<uint32_t>(ctx, out, values.size());
//
// Shaders read their workgroup index with linear_group_id() from shaders/common.glsl (dispatch_groups splits
// large counts over x and y) and must ignore indices past their own element count.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <future>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gpu/context.hpp"

namespace cdtgpu::gpu {

// SPIR-V of shaders/<name>.comp, compiled at build time; throws DeviceError for an unknown name.
std::span<const uint32_t> shader_spirv(std::string_view name);
// Names of all embedded shaders, sorted.
std::vector<std::string> shader_names();

struct PassDesc {
  std::string name;       // shader file name without .comp
  uint32_t buffers = 0;   // storage buffers at bindings 0..buffers-1 of set 0
  uint32_t push_size = 0; // bytes of the push-constant block (0: none)
};

// Move-only; owns its layouts and pipeline. The pipeline compiles on a worker thread (a FIFO queue with one
// worker per core, through the context's pipeline cache): constructors create every pass they might need at
// once, the compiles overlap with each other and with the run, and handle() waits only for the one it needs.
struct Pass {
  VkDevice device = VK_NULL_HANDLE;
  std::string name;
  uint32_t buffers = 0;
  uint32_t push_size = 0;
  uint32_t addressed = 0;  // bit i: binding i holds a buffer's device address (shaders/tri_refs.glsl)
  VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;

  // The pipeline, once compiled; throws DeviceError when its compile failed.
  VkPipeline handle() const;

  Pass() = default;
  Pass(Pass&& o) noexcept;
  Pass& operator=(Pass&& o) noexcept;
  Pass(const Pass&) = delete;
  Pass& operator=(const Pass&) = delete;
  ~Pass();

 private:
  friend Pass create_pass(const Context& ctx, const PassDesc& desc);
  void release();
  mutable VkPipeline pipeline_ = VK_NULL_HANDLE;
  mutable std::shared_future<VkPipeline> compiling_;
};

Pass create_pass(const Context& ctx, const PassDesc& desc);

// Milliseconds the process has spent in handle() waiting for pipelines still compiling.
double pipeline_wait_ms();

}  // namespace cdtgpu::gpu
