// Pipelines from embedded SPIR-V; layouts derived from the declared binding count and push size.
#include "gpu/passes.hpp"

#include <algorithm>
#include <utility>

#include "gpu/check.hpp"

namespace cdtgpu::gpu {
namespace embedded {
struct Shader {
  const char* name;
  const uint32_t* code;
  size_t words;
};
extern const Shader shaders[];
extern const size_t shader_count;
}  // namespace embedded

std::span<const uint32_t> shader_spirv(std::string_view name) {
  for (size_t i = 0; i < embedded::shader_count; ++i)
    if (name == embedded::shaders[i].name) return {embedded::shaders[i].code, embedded::shaders[i].words};
  throw DeviceError("no embedded shader named '" + std::string(name) + "' (expected shaders/" + std::string(name) +
                    ".comp)");
}

std::vector<std::string> shader_names() {
  std::vector<std::string> names;
  for (size_t i = 0; i < embedded::shader_count; ++i) names.emplace_back(embedded::shaders[i].name);
  std::sort(names.begin(), names.end());
  return names;
}

Pass::Pass(Pass&& o) noexcept { *this = std::move(o); }

Pass& Pass::operator=(Pass&& o) noexcept {
  if (this == &o) return *this;
  release();
  device = o.device;
  name = std::move(o.name);
  buffers = o.buffers;
  push_size = o.push_size;
  set_layout = std::exchange(o.set_layout, VK_NULL_HANDLE);
  layout = std::exchange(o.layout, VK_NULL_HANDLE);
  pipeline = std::exchange(o.pipeline, VK_NULL_HANDLE);
  return *this;
}

Pass::~Pass() { release(); }

void Pass::release() {
  if (pipeline) vkDestroyPipeline(device, pipeline, nullptr);
  if (layout) vkDestroyPipelineLayout(device, layout, nullptr);
  if (set_layout) vkDestroyDescriptorSetLayout(device, set_layout, nullptr);
  pipeline = VK_NULL_HANDLE;
  layout = VK_NULL_HANDLE;
  set_layout = VK_NULL_HANDLE;
}

Pass create_pass(const Context& ctx, const PassDesc& desc) {
  std::span<const uint32_t> code = shader_spirv(desc.name);
  Pass pass;
  pass.device = ctx.device;
  pass.name = desc.name;
  pass.buffers = desc.buffers;
  pass.push_size = desc.push_size;

  std::vector<VkDescriptorSetLayoutBinding> bindings(desc.buffers);
  for (uint32_t i = 0; i < desc.buffers; ++i)
    bindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo sl{};
  sl.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  sl.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  sl.bindingCount = desc.buffers;
  sl.pBindings = bindings.data();
  VK_CHECK(vkCreateDescriptorSetLayout(ctx.device, &sl, nullptr, &pass.set_layout));

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, desc.push_size};
  VkPipelineLayoutCreateInfo pl{};
  pl.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO;
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &pass.set_layout;
  pl.pushConstantRangeCount = desc.push_size ? 1 : 0;
  pl.pPushConstantRanges = &range;
  VK_CHECK(vkCreatePipelineLayout(ctx.device, &pl, nullptr, &pass.layout));

  VkShaderModuleCreateInfo mi{};
  mi.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
  mi.codeSize = code.size_bytes();
  mi.pCode = code.data();
  VkShaderModule module = VK_NULL_HANDLE;
  VK_CHECK(vkCreateShaderModule(ctx.device, &mi, nullptr, &module));

  VkComputePipelineCreateInfo ci{};
  ci.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO;
  ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module;
  ci.stage.pName = "main";
  ci.layout = pass.layout;
  VkResult r = vkCreateComputePipelines(ctx.device, VK_NULL_HANDLE, 1, &ci, nullptr, &pass.pipeline);
  vkDestroyShaderModule(ctx.device, module, nullptr);
  if (r != VK_SUCCESS) vk_fail(r, ("vkCreateComputePipelines for pass '" + desc.name + "'").c_str(), __FILE__, __LINE__);
  return pass;
}

}  // namespace cdtgpu::gpu
