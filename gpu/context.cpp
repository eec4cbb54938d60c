// Instance, device choice and logical device; see context.hpp.
#include "gpu/context.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <future>
#include <mutex>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>
#include <utility>

#include "gpu/buffers.hpp"
#include "gpu/device_memory_pool.hpp"
#include "gpu/devices.hpp"
#include "gpu/check.hpp"
#include "gpu/pipeline_cache.hpp"

namespace cdtgpu::gpu {
namespace {

const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

// "123", "64K", "512M", "2G" (powers of 1024).
uint64_t parse_bytes(const char* v) {
  char* end = nullptr;
  const double x = std::strtod(v, &end);
  uint64_t unit = 1;
  if (end && *end) {
    const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(*end)));
    unit = u == 'K' ? 1ull << 10 : u == 'M' ? 1ull << 20 : u == 'G' ? 1ull << 30 : 0;
    if (!unit || end[1]) unit = 0;
  }
  if (end == v || !unit || !(x > 0) || x * double(unit) > 1e18)
    throw DeviceError(std::string("CDTGPU_DEVICE_MEMORY_LIMIT=") + v + ": not a byte count (e.g. 512M, 2G)");
  return static_cast<uint64_t>(x * double(unit));
}

bool env_validation() {
  const char* v = std::getenv("CDTGPU_VALIDATION");
  return v && std::strcmp(v, "1") == 0;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const char* type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

int type_rank(const std::string& type) {
  if (type == "discrete") return 0;
  if (type == "integrated") return 1;
  if (type == "virtual") return 2;
  if (type == "cpu") return 3;
  return 4;
}

// First queue family with compute; prefers one without graphics (a dedicated compute queue).
int compute_family(VkPhysicalDevice pd, uint32_t* timestamp_bits) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  int best = -1;
  for (uint32_t i = 0; i < n; ++i) {
    if (!(fams[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) continue;
    if (best < 0 || (!(fams[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (fams[best].queueFlags & VK_QUEUE_GRAPHICS_BIT)))
      best = static_cast<int>(i);
  }
  if (best >= 0 && timestamp_bits) *timestamp_bits = fams[best].timestampValidBits;
  return best;
}

// The family for copies beside the compute queue (Context::copy_queue): a transfer-only one, else the compute
// family where it has a second queue; -1 when neither. CDTGPU_COPY_QUEUE=compute skips the transfer family and
// =none gives none (the copies then take the compute queue): to compare them in one binary.
int copy_family(VkPhysicalDevice pd, uint32_t compute) {
  const char* env = std::getenv("CDTGPU_COPY_QUEUE");
  const std::string want = env ? env : "";
  if (!want.empty() && want != "transfer" && want != "compute" && want != "none")
    throw DeviceError("CDTGPU_COPY_QUEUE=" + want + ": not transfer, compute or none");
  if (want == "none") return -1;
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  constexpr VkQueueFlags kWork = VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT;
  for (uint32_t i = 0; i < n && want != "compute"; ++i)
    if ((fams[i].queueFlags & VK_QUEUE_TRANSFER_BIT) && !(fams[i].queueFlags & kWork) && fams[i].queueCount > 0)
      return int(i);
  return compute < n && fams[compute].queueCount > 1 ? int(compute) : -1;
}

bool has_extension(VkPhysicalDevice pd, const char* name) {
  uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> exts(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, exts.data());
  for (auto& e : exts)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

DeviceInfo query(VkPhysicalDevice pd, uint32_t index) {
  DeviceInfo d;
  d.index = index;
  VkPhysicalDeviceDriverProperties driver{};
  driver.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES;
  VkPhysicalDeviceSubgroupProperties subgroup{};
  subgroup.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES;
  subgroup.pNext = &driver;
  VkPhysicalDeviceProperties2 props{};
  props.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
  props.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(pd, &props);
  const VkPhysicalDeviceProperties& p = props.properties;
  d.name = p.deviceName;
  d.type = type_name(p.deviceType);
  d.api_version = p.apiVersion;
  d.driver_name = driver.driverName;
  d.driver_info = driver.driverInfo;
  d.max_storage_buffer_range = p.limits.maxStorageBufferRange;
  d.max_shared_memory = p.limits.maxComputeSharedMemorySize;
  d.timestamp_period = p.limits.timestampPeriod;
  d.subgroup_size = subgroup.subgroupSize;
  const VkSubgroupFeatureFlags need_ops =
      VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;
  d.subgroup_ops = (subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) &&
                   (subgroup.supportedOperations & need_ops) == need_ops;

  VkPhysicalDeviceMemoryProperties mem;
  vkGetPhysicalDeviceMemoryProperties(pd, &mem);
  for (uint32_t i = 0; i < mem.memoryHeapCount; ++i) {
    d.heap_sizes.push_back(mem.memoryHeaps[i].size);
    d.heap_device_local.push_back(mem.memoryHeaps[i].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT);
  }

  VkPhysicalDeviceVulkan12Features f12{};
  f12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
  VkPhysicalDeviceFeatures2 f{};
  f.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
  f.pNext = &f12;
  vkGetPhysicalDeviceFeatures2(pd, &f);
  d.float64 = f.features.shaderFloat64;
  d.int64 = f.features.shaderInt64;
  d.int64_atomics = f12.shaderBufferInt64Atomics;
  d.buffer_address = f12.bufferDeviceAddress;
  uint32_t ts_bits = 0;
  int family = compute_family(pd, &ts_bits);
  d.timestamps = family >= 0 && ts_bits > 0 && p.limits.timestampPeriod > 0;
  d.push_descriptors = has_extension(pd, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);

  std::vector<std::string> missing;
  if (VK_API_VERSION_MINOR(p.apiVersion) < 2 && VK_API_VERSION_MAJOR(p.apiVersion) == 1) missing.push_back("Vulkan 1.2");
  if (family < 0) missing.push_back("a compute queue");
  if (!d.float64) missing.push_back("shaderFloat64");
  if (!d.int64) missing.push_back("shaderInt64");
  if (!d.int64_atomics) missing.push_back("shaderBufferInt64Atomics");
  if (!d.timestamps) missing.push_back("timestamps on the compute queue");
  if (!d.subgroup_ops) missing.push_back("subgroup basic/arithmetic/ballot in compute");
  if (d.subgroup_size < 8 || d.subgroup_size > 64) missing.push_back("subgroup size 8..64");
  if (!d.push_descriptors) missing.push_back(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
  if (!d.buffer_address) missing.push_back("bufferDeviceAddress");
  for (size_t i = 0; i < missing.size(); ++i) d.missing += (i ? ", " : "") + missing[i];
  return d;
}

VkInstance make_instance(bool validation, VkDebugUtilsMessengerCreateInfoEXT* messenger_info) {
  VkApplicationInfo app{};
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = "cdtgpu";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ci{};
  ci.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  ci.pApplicationInfo = &app;
  const char* layers[] = {kValidationLayer};
  const char* exts[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
  // Synchronization validation catches a missing barrier between dispatches, the commonest compute bug.
  VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
  VkValidationFeaturesEXT features{};
  features.sType = VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT;
  features.enabledValidationFeatureCount = 1;
  features.pEnabledValidationFeatures = enables;
  if (validation) {
    ci.enabledLayerCount = 1;
    ci.ppEnabledLayerNames = layers;
    ci.enabledExtensionCount = 1;
    ci.ppEnabledExtensionNames = exts;
    features.pNext = messenger_info;  // also reports messages from vkCreateInstance itself
    ci.pNext = &features;
  }
  VkInstance instance = VK_NULL_HANDLE;
  VK_CHECK(vkCreateInstance(&ci, nullptr, &instance));
  return instance;
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  uint32_t n = 0;
  VK_CHECK(vkEnumeratePhysicalDevices(instance, &n, nullptr));
  std::vector<VkPhysicalDevice> pds(n);
  VK_CHECK(vkEnumeratePhysicalDevices(instance, &n, pds.data()));
  pds.resize(n);
  return pds;
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          VkDebugUtilsMessageTypeFlagsEXT, const VkDebugUtilsMessengerCallbackDataEXT* data,
                                          void* user) {
  // Pipelines compile on worker threads (gpu/passes.cpp), so messages may come from several at once.
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  auto* messages = static_cast<std::vector<std::string>*>(user);
  std::string m = severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error: " : "warning: ";
  m += data->pMessage ? data->pMessage : "";
  messages->push_back(m);
  return VK_FALSE;
}

std::string mib(uint64_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

}  // namespace

bool validation_layer_available() {
  uint32_t n = 0;
  if (vkEnumerateInstanceLayerProperties(&n, nullptr) != VK_SUCCESS) return false;
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (auto& l : layers)
    if (std::strcmp(l.layerName, kValidationLayer) == 0) return true;
  return false;
}

std::vector<DeviceInfo> list_devices() {
  // Once a process: each call made and destroyed an instance of its own. Under MPI a rank listed the devices to
  // pick its GPU, then again to open its tile devices, 0.1-0.5 s each while the other ranks started too.
  static std::mutex mutex;
  static std::optional<std::vector<DeviceInfo>> listed;
  std::lock_guard<std::mutex> lock(mutex);
  if (listed) return *listed;
  VkInstance instance = make_instance(false, nullptr);
  std::vector<DeviceInfo> out;
  try {
    auto pds = physical_devices(instance);
    for (uint32_t i = 0; i < pds.size(); ++i) out.push_back(query(pds[i], i));
  } catch (...) {
    vkDestroyInstance(instance, nullptr);
    throw;
  }
  vkDestroyInstance(instance, nullptr);
  listed = out;
  return out;
}

size_t pick_device(const std::vector<DeviceInfo>& devices, const std::string& override_name) {
  if (devices.empty()) throw DeviceError("no Vulkan device found (is a Vulkan driver installed?)");
  if (!override_name.empty()) {
    bool numeric = std::all_of(override_name.begin(), override_name.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
    size_t pick = devices.size();
    if (numeric) {
      size_t i = std::stoul(override_name);
      if (i >= devices.size())
        throw DeviceError("device index " + override_name + " out of range: " + std::to_string(devices.size()) +
                          " device(s) found");
      pick = i;
    } else {
      for (size_t i = 0; i < devices.size() && pick == devices.size(); ++i)
        if (lower(devices[i].name).find(lower(override_name)) != std::string::npos) pick = i;
      if (pick == devices.size()) throw DeviceError("no Vulkan device name contains '" + override_name + "'");
    }
    if (!devices[pick].missing.empty())
      throw DeviceError("device '" + devices[pick].name + "' cannot run cdtgpu: it lacks " + devices[pick].missing);
    return pick;
  }
  size_t best = devices.size();
  for (size_t i = 0; i < devices.size(); ++i) {
    if (!devices[i].missing.empty()) continue;
    if (best == devices.size() || type_rank(devices[i].type) < type_rank(devices[best].type)) best = i;
  }
  if (best == devices.size()) {
    std::string m = "no Vulkan device can run cdtgpu:";
    for (auto& d : devices) m += " '" + d.name + "' lacks " + d.missing + ";";
    throw DeviceError(m);
  }
  return best;
}

std::string describe_devices(const std::string& override_name) {
  auto devices = list_devices();
  std::ostringstream os;
  size_t picked = devices.size();
  std::string pick_error;
  try {
    picked = pick_device(devices, override_name);
  } catch (const DeviceError& e) {
    pick_error = e.what();
  }
  for (auto& d : devices) {
    os << (d.index == picked ? "* " : "  ") << d.index << ": " << d.name << " (" << d.type << ")\n";
    os << "    driver: " << d.driver_name << " " << d.driver_info << ", Vulkan " << VK_API_VERSION_MAJOR(d.api_version)
       << "." << VK_API_VERSION_MINOR(d.api_version) << "." << VK_API_VERSION_PATCH(d.api_version) << "\n";
    os << "    memory heaps:";
    for (size_t h = 0; h < d.heap_sizes.size(); ++h)
      os << " " << mib(d.heap_sizes[h]) << (d.heap_device_local[h] ? " (device-local)" : "");
    os << "\n";
    os << "    float64: " << (d.float64 ? "yes" : "no") << ", int64: " << (d.int64 ? "yes" : "no")
       << ", int64 buffer atomics: " << (d.int64_atomics ? "yes" : "no")
       << ", timestamps: " << (d.timestamps ? "yes" : "no") << "\n";
    os << "    maxStorageBufferRange: " << d.max_storage_buffer_range << " bytes (" << mib(d.max_storage_buffer_range)
       << "), subgroup size: " << d.subgroup_size << ", shared memory: " << d.max_shared_memory << " bytes\n";
    os << "    usable: " << (d.missing.empty() ? "yes" : "no, lacks " + d.missing) << "\n";
  }
  if (picked < devices.size())
    os << "picked: " << picked << " (" << devices[picked].name << ")\n";
  else
    os << "picked: none: " << pick_error << "\n";
  return os.str();
}

namespace {
void save_cache(Context& c) {
  if (!c.pipeline_cache) return;
  store_pipeline_cache(c);
  vkDestroyPipelineCache(c.device, c.pipeline_cache, nullptr);
  c.pipeline_cache = VK_NULL_HANDLE;
}
}  // namespace

void store_pipeline_cache(const Context& c) {
  if (!c.pipeline_cache) return;
  size_t n = 0;
  std::vector<char> data;
  if (vkGetPipelineCacheData(c.device, c.pipeline_cache, &n, nullptr) == VK_SUCCESS && n > 0) {
    data.resize(n);
    if (vkGetPipelineCacheData(c.device, c.pipeline_cache, &n, data.data()) != VK_SUCCESS) data.clear();
    data.resize(std::min(n, data.size()));
  }
  if (!data.empty() && !c.pipeline_cache_file.empty() &&
      (data.size() != c.pipeline_cache_loaded || std::hash<std::string_view>{}({data.data(), data.size()}) != c.pipeline_cache_hash))
    save_pipeline_cache(c.pipeline_cache_file, c.props, data);
}

namespace {

void release(Context& c) {
  // Steps in -v: a single run closes its device beside the writing, and waits for it before it exits.
  auto t = std::chrono::steady_clock::now();
  auto step = [&t](const char* what) {
    const auto now = std::chrono::steady_clock::now();
    spdlog::debug("gpu close: {}: {:.1f} ms", what, std::chrono::duration<double, std::milli>(now - t).count());
    t = now;
  };
  if (c.device) {
    vkDeviceWaitIdle(c.device);
    c.staging.reset();
    c.temp_pool.reset();
    // Buffers still holding it give their ranges to nothing.
    if (const auto pool = c.memory_pool.exchange(nullptr)) pool->free_blocks();
    step("staging and device memory pool");
    save_cache(c);
    step("pipeline cache");
    if (c.pool) vkDestroyCommandPool(c.device, c.pool, nullptr);
    if (c.copy_pool) vkDestroyCommandPool(c.device, c.copy_pool, nullptr);
    vkDestroyDevice(c.device, nullptr);
    step("device");
  }
  if (c.messenger) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(c.instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(c.instance, c.messenger, nullptr);
  }
  if (c.instance) {
    vkDestroyInstance(c.instance, nullptr);
    step("instance");
  }
  c.instance = VK_NULL_HANDLE;
  c.messenger = VK_NULL_HANDLE;
  c.device = VK_NULL_HANDLE;
  c.pool = VK_NULL_HANDLE;
  c.copy_pool = VK_NULL_HANDLE;
  c.copy_queue = VK_NULL_HANDLE;
}
}  // namespace

Context::Context(Context&& o) noexcept { *this = std::move(o); }

Context& Context::operator=(Context&& o) noexcept {
  if (this == &o) return *this;
  release(*this);
  instance = std::exchange(o.instance, VK_NULL_HANDLE);
  messenger = std::exchange(o.messenger, VK_NULL_HANDLE);
  physical = std::exchange(o.physical, VK_NULL_HANDLE);
  device = std::exchange(o.device, VK_NULL_HANDLE);
  queue = std::exchange(o.queue, VK_NULL_HANDLE);
  pool = std::exchange(o.pool, VK_NULL_HANDLE);
  copy_queue = std::exchange(o.copy_queue, VK_NULL_HANDLE);
  copy_family = o.copy_family;
  copy_pool = std::exchange(o.copy_pool, VK_NULL_HANDLE);
  queue_family = o.queue_family;
  props = o.props;
  memory = o.memory;
  info = o.info;
  validation = o.validation;
  cmd_push_descriptor_set = o.cmd_push_descriptor_set;
  shader_stats = o.shader_stats;
  messages_ = std::move(o.messages_);
  o.messages_ = std::make_unique<std::vector<std::string>>();
  staging = std::move(o.staging);
  temp_pool = std::move(o.temp_pool);
  pipeline_cache = std::exchange(o.pipeline_cache, VK_NULL_HANDLE);
  pipeline_cache_file = std::move(o.pipeline_cache_file);
  pipeline_cache_loaded = o.pipeline_cache_loaded;
  pipeline_cache_hash = o.pipeline_cache_hash;
  memory_budget = std::exchange(o.memory_budget, std::make_shared<MemoryBudget>());
  memory_pool.store(o.memory_pool.exchange(nullptr));
  return *this;
}

Context::~Context() { release(*this); }

uint64_t device_memory_limit_from_env() {
  const char* v = std::getenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  return v && *v ? parse_bytes(v) : 0;
}

Context create_context(const ContextOptions& options) {
  Context ctx;
  ctx.memory_budget->limit = device_memory_limit_from_env();
  // Steps of the start in -v: it takes ~170 ms on the H100 machine, most of a small run.
  auto t = std::chrono::steady_clock::now();
  auto step = [&t](const char* what) {
    const auto now = std::chrono::steady_clock::now();
    spdlog::debug("gpu start: {}: {:.1f} ms", what, std::chrono::duration<double, std::milli>(now - t).count());
    t = now;
  };
  bool want = options.validation || env_validation();
  bool have = want && validation_layer_available();  // the loader reads every layer's manifest for it
  if (env_validation() && !have)
    throw DeviceError("CDTGPU_VALIDATION=1 but the layer VK_LAYER_KHRONOS_validation is not installed");
  ctx.validation = want && have;

  VkDebugUtilsMessengerCreateInfoEXT mi{};
  mi.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
  mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                   VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mi.pfnUserCallback = on_message;
  mi.pUserData = ctx.messages_.get();

  ctx.instance = make_instance(ctx.validation, &mi);
  step("instance");
  if (ctx.validation) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(ctx.instance, "vkCreateDebugUtilsMessengerEXT"));
    if (!create) throw DeviceError("validation layer loaded but vkCreateDebugUtilsMessengerEXT is missing");
    VK_CHECK(create(ctx.instance, &mi, nullptr, &ctx.messenger));
  }

  auto pds = physical_devices(ctx.instance);
  std::vector<DeviceInfo> infos;
  for (uint32_t i = 0; i < pds.size(); ++i) infos.push_back(query(pds[i], i));
  size_t pick = 0;
  if (options.nth_gpu >= 0 && options.device.empty()) {
    const std::vector<size_t> gpus = select_devices(infos, "all");
    pick = gpus[size_t(options.nth_gpu) % gpus.size()];
    ctx.shared = size_t(options.processes_on_host) > gpus.size();
  } else {
    pick = pick_device(infos, options.device);
  }
  ctx.physical = pds[pick];
  ctx.info = infos[pick];
  vkGetPhysicalDeviceProperties(ctx.physical, &ctx.props);
  vkGetPhysicalDeviceMemoryProperties(ctx.physical, &ctx.memory);
  ctx.queue_family = static_cast<uint32_t>(compute_family(ctx.physical, nullptr));
  if (options.hardware_only && ctx.info.type == "cpu")
    throw DeviceError(ctx.info.name + " is a CPU Vulkan driver, not a GPU");
  step("physical devices");

  const float priorities[] = {1.0f, 1.0f};
  const int copies = copy_family(ctx.physical, ctx.queue_family);
  VkDeviceQueueCreateInfo qi[2]{};
  qi[0].sType = qi[1].sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
  qi[0].queueFamilyIndex = ctx.queue_family;
  qi[0].queueCount = copies == int(ctx.queue_family) ? 2 : 1;
  qi[0].pQueuePriorities = qi[1].pQueuePriorities = priorities;
  qi[1].queueFamilyIndex = uint32_t(copies);
  qi[1].queueCount = 1;
  const uint32_t families = copies >= 0 && copies != int(ctx.queue_family) ? 2 : 1;

  VkPhysicalDeviceVulkan12Features f12{};
  f12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
  f12.shaderBufferInt64Atomics = VK_TRUE;
  f12.shaderSharedInt64Atomics = VK_FALSE;
  f12.bufferDeviceAddress = VK_TRUE;
  VkPhysicalDeviceFeatures2 f{};
  f.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
  f.pNext = &f12;
  f.features.shaderFloat64 = VK_TRUE;
  f.features.shaderInt64 = VK_TRUE;

  const char* exts[] = {VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME,
                        VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME};
  const char* stats_env = std::getenv("CDTGPU_SHADER_STATS");
  ctx.shader_stats = stats_env && std::string(stats_env) == "1" &&
                     has_extension(ctx.physical, VK_KHR_PIPELINE_EXECUTABLE_PROPERTIES_EXTENSION_NAME);
  VkPhysicalDevicePipelineExecutablePropertiesFeaturesKHR fx{};
  fx.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PIPELINE_EXECUTABLE_PROPERTIES_FEATURES_KHR;
  fx.pipelineExecutableInfo = VK_TRUE;
  if (ctx.shader_stats) f12.pNext = &fx;
  VkDeviceCreateInfo di{};
  di.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
  di.pNext = &f;
  di.queueCreateInfoCount = families;
  di.pQueueCreateInfos = qi;
  di.enabledExtensionCount = ctx.shader_stats ? 2 : 1;
  di.ppEnabledExtensionNames = exts;
  VK_CHECK(vkCreateDevice(ctx.physical, &di, nullptr, &ctx.device));
  step("device");
  vkGetDeviceQueue(ctx.device, ctx.queue_family, 0, &ctx.queue);
  if (copies >= 0) {
    ctx.copy_family = uint32_t(copies);
    vkGetDeviceQueue(ctx.device, ctx.copy_family, copies == int(ctx.queue_family) ? 1 : 0, &ctx.copy_queue);
  }
  ctx.cmd_push_descriptor_set =
      reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(ctx.device, "vkCmdPushDescriptorSetKHR"));
  if (!ctx.cmd_push_descriptor_set) throw DeviceError("vkCmdPushDescriptorSetKHR not found on " + ctx.info.name);

  // Pinning host memory (~0.25 ms per MB) would otherwise follow everything else on the start's path.
  std::future<void> staging;
  if (options.staging_bytes)
    staging = std::async(std::launch::async, [&ctx, &options] {
      const auto t0 = std::chrono::steady_clock::now();
      reserve_staging(ctx, options.staging_bytes);
      if (options.staging_ms)
        *options.staging_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    });

  std::future<void> pool;
  // Not under a cap, which counts each buffer as the driver would, nor on a GPU other processes take too.
  if (options.device_pool_bytes && !ctx.memory_budget->limit && !ctx.shared)
    pool = std::async(std::launch::async, [&ctx, &options] {
      try {
        ctx.memory_pool.store(make_device_pool(ctx, options.device_pool_bytes));
      } catch (const std::exception& e) {  // the buffers then take memory of their own, as without a pool
        spdlog::debug("no device memory pool: {}", e.what());
      }
    });

  VkCommandPoolCreateInfo pi{};
  pi.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = ctx.queue_family;
  VK_CHECK(vkCreateCommandPool(ctx.device, &pi, nullptr, &ctx.pool));
  if (ctx.copy_queue) {
    pi.queueFamilyIndex = ctx.copy_family;
    VK_CHECK(vkCreateCommandPool(ctx.device, &pi, nullptr, &ctx.copy_pool));
  }

  ctx.pipeline_cache_file = pipeline_cache_path(ctx.props);
  const std::vector<char> seed = load_pipeline_cache(ctx.pipeline_cache_file, ctx.props);
  VkPipelineCacheCreateInfo ci{};
  ci.sType = VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO;
  ci.initialDataSize = seed.size();
  ci.pInitialData = seed.empty() ? nullptr : seed.data();
  // A driver may still refuse data that passed our checks (it validates its own header): start empty then.
  if (vkCreatePipelineCache(ctx.device, &ci, nullptr, &ctx.pipeline_cache) != VK_SUCCESS && !seed.empty()) {
    ci.initialDataSize = 0;
    ci.pInitialData = nullptr;
    VK_CHECK(vkCreatePipelineCache(ctx.device, &ci, nullptr, &ctx.pipeline_cache));
  } else if (!seed.empty()) {
    ctx.pipeline_cache_loaded = seed.size();
    ctx.pipeline_cache_hash = std::hash<std::string_view>{}({seed.data(), seed.size()});
  }
  step("command pool and pipeline cache");
  if (staging.valid()) {
    staging.get();
    step("staging memory (after the cache)");
  }
  if (pool.valid()) {
    pool.get();
    step("device memory pool (after the staging)");
  }
  return ctx;
}

}  // namespace cdtgpu::gpu
