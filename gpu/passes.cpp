// Pipelines from embedded SPIR-V; layouts derived from the declared binding count and push size.
#include "gpu/passes.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <unordered_set>
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
  addressed = o.addressed;
  set_layout = std::exchange(o.set_layout, VK_NULL_HANDLE);
  layout = std::exchange(o.layout, VK_NULL_HANDLE);
  pipeline_ = std::exchange(o.pipeline_, VK_NULL_HANDLE);
  compiling_ = std::move(o.compiling_);
  o.compiling_ = {};
  return *this;
}

Pass::~Pass() { release(); }

namespace {
std::atomic<int64_t> wait_ns{0};
}  // namespace

double pipeline_wait_ms() { return double(wait_ns.load()) * 1e-6; }

VkPipeline Pass::handle() const {
  if (!pipeline_ && compiling_.valid()) {
    const auto t = std::chrono::steady_clock::now();
    pipeline_ = compiling_.get();
    wait_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t).count();
  }
  return pipeline_;
}

void Pass::release() {
  if (compiling_.valid()) {
    compiling_.wait();  // the worker still uses the layout
    try {
      handle();
    } catch (...) {  // a failed compile left nothing to destroy
    }
    compiling_ = {};
  }
  if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
  if (layout) vkDestroyPipelineLayout(device, layout, nullptr);
  if (set_layout) vkDestroyDescriptorSetLayout(device, set_layout, nullptr);
  pipeline_ = VK_NULL_HANDLE;
  layout = VK_NULL_HANDLE;
  set_layout = VK_NULL_HANDLE;
}

namespace {

// Pipeline compiles in the order they were asked for, one worker per core. First come, first compiled: the
// passes constructors create first are the ones a run uses first.
class CompileQueue {
 public:
  static CompileQueue& get() {
    static CompileQueue queue;
    return queue;
  }
  void push(std::function<void()> job) {
    {
      std::lock_guard lock(mutex_);
      jobs_.push_back(std::move(job));
      if (workers_.size() < max_workers_ && idle_ == 0) workers_.emplace_back([this] { work(); });
    }
    ready_.notify_one();
  }
  ~CompileQueue() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    ready_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

 private:
  void work() {
    std::unique_lock lock(mutex_);
    for (;;) {
      ++idle_;
      ready_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
      --idle_;
      if (jobs_.empty()) return;  // stopping
      std::function<void()> job = std::move(jobs_.front());
      jobs_.pop_front();
      lock.unlock();
      job();
      lock.lock();
    }
  }
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> jobs_;
  std::vector<std::thread> workers_;
  size_t max_workers_ = std::max(1u, std::thread::hardware_concurrency());
  size_t idle_ = 0;
  bool stop_ = false;
};

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

// Bit i set when the shader's binding i is a block holding a buffer reference (a PhysicalStorageBuffer
// pointer): the recorder binds an address there, not the buffer (gpu/recorder.cpp).
uint32_t addressed_bindings(std::span<const uint32_t> code) {
  constexpr uint32_t kOpTypeStruct = 30, kOpTypePointer = 32, kOpVariable = 59, kOpDecorate = 71;
  constexpr uint32_t kDecorationBinding = 33, kPhysicalStorageBuffer = 5349;
  std::unordered_map<uint32_t, uint32_t> pointee, binding_of;  // pointer type -> pointee; variable -> binding
  std::unordered_map<uint32_t, uint32_t> variable_type;
  std::unordered_set<uint32_t> address_pointers, address_structs;
  std::vector<std::pair<uint32_t, std::vector<uint32_t>>> structs;
  for (size_t i = 5; i < code.size();) {  // after the header
    const uint32_t words = code[i] >> 16, op = code[i] & 0xFFFF;
    if (words == 0 || i + words > code.size()) break;
    const uint32_t* w = &code[i];
    if (op == kOpTypePointer && words >= 4) {
      pointee[w[1]] = w[3];
      if (w[2] == kPhysicalStorageBuffer) address_pointers.insert(w[1]);
    } else if (op == kOpTypeStruct) {
      structs.push_back({w[1], std::vector<uint32_t>(w + 2, w + words)});
    } else if (op == kOpVariable && words >= 4) {
      variable_type[w[2]] = w[1];
    } else if (op == kOpDecorate && words >= 4 && w[2] == kDecorationBinding) {
      binding_of[w[1]] = w[3];
    }
    i += words;
  }
  for (const auto& [id, members] : structs)
    for (uint32_t m : members)
      if (address_pointers.count(m)) address_structs.insert(id);
  uint32_t mask = 0;
  for (const auto& [var, binding] : binding_of) {
    auto type = variable_type.find(var);
    if (type == variable_type.end() || binding >= 32) continue;
    auto block = pointee.find(type->second);
    if (block != pointee.end() && address_structs.count(block->second)) mask |= 1u << binding;
  }
  return mask;
}

}  // namespace

Pass create_pass(const Context& ctx, const PassDesc& desc) {
  std::span<const uint32_t> code = shader_spirv(desc.name);
  Pass pass;
  pass.device = ctx.device;
  pass.name = desc.name;
  pass.buffers = desc.buffers;
  pass.push_size = desc.push_size;
  pass.addressed = addressed_bindings(code);

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

  // The compile itself, on a worker: what it needs is copied or outlives the pass (the context, the SPIR-V).
  const Context* c = &ctx;
  const VkPipelineLayout layout = pass.layout;
  const std::string name = desc.name;
  auto job = std::make_shared<std::packaged_task<VkPipeline()>>([c, layout, name, code] {
    VkShaderModuleCreateInfo mi{};
    mi.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO;
    mi.codeSize = code.size_bytes();
    mi.pCode = code.data();
    VkShaderModule module = VK_NULL_HANDLE;
    VK_CHECK(vkCreateShaderModule(c->device, &mi, nullptr, &module));
    VkComputePipelineCreateInfo ci{};
    ci.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO;
    ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
    ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    ci.stage.module = module;
    ci.stage.pName = "main";
    ci.layout = layout;
    if (c->shader_stats) ci.flags |= VK_PIPELINE_CREATE_CAPTURE_STATISTICS_BIT_KHR;
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkResult r = vkCreateComputePipelines(c->device, c->pipeline_cache, 1, &ci, nullptr, &pipeline);
    vkDestroyShaderModule(c->device, module, nullptr);
    if (r != VK_SUCCESS) vk_fail(r, ("vkCreateComputePipelines for pass '" + name + "'").c_str(), __FILE__, __LINE__);
    if (c->shader_stats) print_statistics(*c, name, pipeline);
    return pipeline;
  });
  pass.compiling_ = job->get_future().share();
  CompileQueue::get().push([job] { (*job)(); });
  return pass;
}

}  // namespace cdtgpu::gpu
