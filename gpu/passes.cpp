// Pipelines from embedded SPIR-V; layouts derived from the declared binding count and push size.
#include "gpu/passes.hpp"

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

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

namespace {

// One line per pipeline executable: its name and every statistic the driver reports.
void print_statistics(const Context& ctx, const std::string& name, VkPipeline pipeline) {
  auto props = reinterpret_cast<PFN_vkGetPipelineExecutablePropertiesKHR>(
      vkGetDeviceProcAddr(ctx.device, "vkGetPipelineExecutablePropertiesKHR"));
  auto stats = reinterpret_cast<PFN_vkGetPipelineExecutableStatisticsKHR>(
      vkGetDeviceProcAddr(ctx.device, "vkGetPipelineExecutableStatisticsKHR"));
  if (!props || !stats) return;
  VkPipelineInfoKHR pi{VK_STRUCTURE_TYPE_PIPELINE_INFO_KHR, nullptr, pipeline};
  uint32_t count = 0;
  props(ctx.device, &pi, &count, nullptr);
  for (uint32_t e = 0; e < count; ++e) {
    VkPipelineExecutableInfoKHR ei{VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_INFO_KHR, nullptr, pipeline, e};
    uint32_t n = 0;
    stats(ctx.device, &ei, &n, nullptr);
    VkPipelineExecutableStatisticKHR blank{};
    blank.sType = VK_STRUCTURE_TYPE_PIPELINE_EXECUTABLE_STATISTIC_KHR;
    std::vector<VkPipelineExecutableStatisticKHR> v(n, blank);
    stats(ctx.device, &ei, &n, v.data());
    std::string line = "shader stats: " + name + ":";
    for (const auto& st : v) {
      line += std::string(" ") + st.name + "=";
      switch (st.format) {
        case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_BOOL32_KHR:
          line += st.value.b32 ? "1" : "0";
          break;
        case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_INT64_KHR:
          line += std::to_string(st.value.i64);
          break;
        case VK_PIPELINE_EXECUTABLE_STATISTIC_FORMAT_UINT64_KHR:
          line += std::to_string(st.value.u64);
          break;
        default:
          line += std::to_string(st.value.f64);
      }
    }
    std::fprintf(stderr, "%s\n", line.c_str());
  }
}

}  // namespace

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
  if (ctx.shader_stats) ci.flags |= VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR;
  VkResult r = vkCreateComputePipelines(ctx.device, VK_NULL_HANDLE, 1, &ci, nullptr, &pass.pipeline);
  vkDestroyShaderModule(ctx.device, module, nullptr);
  if (r != VK_SUCCESS) vk_fail(r, ("vkCreateComputePipelines for pass '" + desc.name + "'").c_str(), __FILE__, __LINE__);
  if (ctx.shader_stats) print_statistics(ctx, desc.name, pass.pipeline);
  return pass;
}

}  // namespace cdtgpu::gpu
