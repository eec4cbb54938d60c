// Probe: what issue 29's option (1) would cost on a lent host. Host memory imported into Vulkan
// (VK_EXT_external_memory_host) in chunks, then the device's copies straight into it, on every GPU at once,
// against copies into a pinned staging buffer. Usage: import_probe GB_PER_DEVICE [CHUNK_MB]
// Not part of the build (docs/tiles.md, "Not done yet", has its figures):
//   g++ -O2 -std=c++20 scripts/import_probe.cpp -o import_probe -lvulkan -lpthread
// PROBE_ANY_DEVICE=1 lets it run on lavapipe too (import_probe 2 256), to check the path, not its speed.
#include <vulkan/vulkan.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

#define CK(x)                                                                  \
  do {                                                                         \
    VkResult r_ = (x);                                                         \
    if (r_ != VK_SUCCESS) {                                                    \
      std::fprintf(stderr, "%s failed: %d (line %d)\n", #x, int(r_), __LINE__); \
      std::exit(1);                                                            \
    }                                                                          \
  } while (0)

using Clock = std::chrono::steady_clock;
static double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

struct Dev {
  VkPhysicalDevice phys{};
  VkDevice dev{};
  VkQueue queue{};
  uint32_t family = 0;
  VkDeviceSize align = 4096;
  VkPhysicalDeviceMemoryProperties mem{};
  PFN_vkGetMemoryHostPointerPropertiesEXT host_props{};
};

static uint32_t pick_type(const Dev& d, uint32_t bits, VkMemoryPropertyFlags want) {
  for (uint32_t i = 0; i < d.mem.memoryTypeCount; ++i)
    if ((bits & (1u << i)) && (d.mem.memoryTypes[i].propertyFlags & want) == want) return i;
  std::fprintf(stderr, "no memory type\n");
  std::exit(1);
}

static VkBuffer make_buffer(const Dev& d, VkDeviceSize bytes, bool external) {
  VkExternalMemoryBufferCreateInfo ext{VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO};
  ext.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.pNext = external ? &ext : nullptr;
  bi.size = bytes;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer b;
  CK(vkCreateBuffer(d.dev, &bi, nullptr, &b));
  return b;
}

static VkDeviceMemory alloc_bind(const Dev& d, VkBuffer b, VkMemoryPropertyFlags want, void* host = nullptr) {
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(d.dev, b, &req);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  VkImportMemoryHostPointerInfoEXT imp{VK_STRUCTURE_TYPE_IMPORT_MEMORY_HOST_POINTER_INFO_EXT};
  if (host) {
    VkMemoryHostPointerPropertiesEXT hp{VK_STRUCTURE_TYPE_MEMORY_HOST_POINTER_PROPERTIES_EXT};
    CK(d.host_props(d.dev, VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT, host, &hp));
    imp.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_HOST_ALLOCATION_BIT_EXT;
    imp.pHostPointer = host;
    ai.pNext = &imp;
    ai.memoryTypeIndex = pick_type(d, req.memoryTypeBits & hp.memoryTypeBits, 0);
  } else {
    ai.memoryTypeIndex = pick_type(d, req.memoryTypeBits, want);
  }
  VkDeviceMemory m;
  CK(vkAllocateMemory(d.dev, &ai, nullptr, &m));
  CK(vkBindBufferMemory(d.dev, b, m, 0));
  return m;
}

// Copies src into each of dst (whole), one submit, timed.
static double copy_all(const Dev& d, VkBuffer src, const std::vector<VkBuffer>& dst, VkDeviceSize bytes) {
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.queueFamilyIndex = d.family;
  VkCommandPool pool;
  CK(vkCreateCommandPool(d.dev, &pi, nullptr, &pool));
  VkCommandBufferAllocateInfo ca{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ca.commandPool = pool;
  ca.commandBufferCount = 1;
  VkCommandBuffer cb;
  CK(vkAllocateCommandBuffers(d.dev, &ca, &cb));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  CK(vkBeginCommandBuffer(cb, &bi));
  for (VkBuffer b : dst) {
    VkBufferCopy r{0, 0, bytes};
    vkCmdCopyBuffer(cb, src, b, 1, &r);
  }
  CK(vkEndCommandBuffer(cb));
  VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence f;
  CK(vkCreateFence(d.dev, &fi, nullptr, &f));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cb;
  const auto t = Clock::now();
  CK(vkQueueSubmit(d.queue, 1, &si, f));
  CK(vkWaitForFences(d.dev, 1, &f, VK_TRUE, UINT64_MAX));
  const double ms = ms_since(t);
  vkDestroyFence(d.dev, f, nullptr);
  vkDestroyCommandPool(d.dev, pool, nullptr);
  return ms;
}

int main(int argc, char** argv) {
  const double gb = argc > 1 ? std::atof(argv[1]) : 12;
  // Chunks of 2 GiB (NVIDIA's largest allocation is 4 GiB) unless told (MB): lavapipe's copies of 2 GiB crash.
  const VkDeviceSize chunk = (argc > 2 ? VkDeviceSize(std::atoll(argv[2])) : 2048) << 20;
  const size_t chunks = size_t(gb * (1 << 30) / chunk);
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo ii{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ii.pApplicationInfo = &app;
  VkInstance inst;
  CK(vkCreateInstance(&ii, nullptr, &inst));
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(inst, &n, nullptr);
  std::vector<VkPhysicalDevice> phys(n);
  vkEnumeratePhysicalDevices(inst, &n, phys.data());
  std::vector<Dev> devs;
  for (VkPhysicalDevice p : phys) {
    VkPhysicalDeviceProperties pr;
    vkGetPhysicalDeviceProperties(p, &pr);
    // Every discrete GPU; a CPU device (lavapipe) only where there is none, to check the code path.
    if (pr.deviceType != VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU && !std::getenv("PROBE_ANY_DEVICE")) continue;
    Dev d;
    d.phys = p;
    VkPhysicalDeviceExternalMemoryHostPropertiesEXT hp{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_MEMORY_HOST_PROPERTIES_EXT};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    p2.pNext = &hp;
    vkGetPhysicalDeviceProperties2(p, &p2);
    d.align = hp.minImportedHostPointerAlignment;
    vkGetPhysicalDeviceMemoryProperties(p, &d.mem);
    uint32_t fc = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(p, &fc, nullptr);
    std::vector<VkQueueFamilyProperties> fam(fc);
    vkGetPhysicalDeviceQueueFamilyProperties(p, &fc, fam.data());
    d.family = UINT32_MAX;
    for (uint32_t i = 0; i < fc; ++i)  // the copy engines' family where there is one
      if ((fam[i].queueFlags & VK_QUEUE_TRANSFER_BIT) && !(fam[i].queueFlags & (VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT)))
        d.family = i;
    if (d.family == UINT32_MAX) d.family = 0;
    float prio = 1;
    VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    qi.queueFamilyIndex = d.family;
    qi.queueCount = 1;
    qi.pQueuePriorities = &prio;
    const char* ext[] = {VK_EXT_EXTERNAL_MEMORY_HOST_EXTENSION_NAME};
    VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    di.enabledExtensionCount = 1;
    di.ppEnabledExtensionNames = ext;
    CK(vkCreateDevice(p, &di, nullptr, &d.dev));
    vkGetDeviceQueue(d.dev, d.family, 0, &d.queue);
    d.host_props = reinterpret_cast<PFN_vkGetMemoryHostPointerPropertiesEXT>(
        vkGetDeviceProcAddr(d.dev, "vkGetMemoryHostPointerPropertiesEXT"));
    std::printf("device %zu: %s, copy family %u, import alignment %llu\n", devs.size(), pr.deviceName, d.family,
                (unsigned long long)d.align);
    devs.push_back(d);
  }
  const size_t D = devs.size();
  // Each device's part of one host range, touched on all cores first (as the output's room is, beside the tiles).
  const size_t bytes = chunks * chunk * D;
  char* host = static_cast<char*>(std::aligned_alloc(size_t(2) << 20, bytes));
  auto t = Clock::now();
  {
    std::vector<std::thread> th;
    const unsigned T = std::thread::hardware_concurrency();
    for (unsigned i = 0; i < T; ++i)
      th.emplace_back([=] {
        for (size_t at = bytes / T * i; at < bytes / T * (i + 1); at += 4096) host[at] = 1;
      });
    for (auto& x : th) x.join();
  }
  std::printf("%.1f GB of host memory touched in %.0f ms\n", bytes / 1e9, ms_since(t));
  for (int round = 0; round < 2; ++round) {
    std::vector<double> import_ms(D), copy_ms(D), pinned_ms(D), pinned_alloc_ms(D);
    std::vector<std::thread> th;
    const auto t0 = Clock::now();
    for (size_t k = 0; k < D; ++k)
      th.emplace_back([&, k] {
        const Dev& d = devs[k];
        auto t = Clock::now();
        std::vector<VkBuffer> dst;
        std::vector<VkDeviceMemory> mem;
        for (size_t c = 0; c < chunks; ++c) {
          dst.push_back(make_buffer(d, chunk, true));
          mem.push_back(alloc_bind(d, dst.back(), 0, host + (k * chunks + c) * chunk));
        }
        import_ms[k] = ms_since(t);
        VkBuffer src = make_buffer(d, chunk, false);
        VkDeviceMemory sm = alloc_bind(d, src, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        copy_ms[k] = copy_all(d, src, dst, chunk);
        t = Clock::now();
        VkBuffer pin = make_buffer(d, chunk, false);
        VkDeviceMemory pm = alloc_bind(d, pin, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
        pinned_alloc_ms[k] = ms_since(t);
        std::vector<VkBuffer> pins(chunks, pin);
        pinned_ms[k] = copy_all(d, src, pins, chunk);
        vkDestroyBuffer(d.dev, pin, nullptr);
        vkFreeMemory(d.dev, pm, nullptr);
        vkDestroyBuffer(d.dev, src, nullptr);
        vkFreeMemory(d.dev, sm, nullptr);
        t = Clock::now();
        for (size_t c = 0; c < chunks; ++c) {
          vkDestroyBuffer(d.dev, dst[c], nullptr);
          vkFreeMemory(d.dev, mem[c], nullptr);
        }
        std::printf("round %d device %zu: imported %.1f GB in %.0f ms (%.2f ms/GB), freed in %.0f ms; device -> "
                    "imported %.1f GB in %.0f ms (%.1f GB/s); device -> pinned chunk-sized buffer x%zu in %.0f ms (%.1f GB/s), "
                    "that buffer allocated in %.0f ms\n",
                    round, k, chunks * chunk / 1e9, import_ms[k], import_ms[k] / (chunks * chunk / 1e9), ms_since(t),
                    chunks * chunk / 1e9, copy_ms[k], chunks * chunk / 1e6 / copy_ms[k], chunks, pinned_ms[k],
                    chunks * chunk / 1e6 / pinned_ms[k], pinned_alloc_ms[k]);
      });
    for (auto& x : th) x.join();
    std::printf("round %d: all devices at once, %.0f ms\n", round, ms_since(t0));
  }
  for (Dev& d : devs) vkDestroyDevice(d.dev, nullptr);
  vkDestroyInstance(inst, nullptr);
  std::free(host);
}
