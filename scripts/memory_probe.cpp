// Probe: what the driver's allocations cost a tiled run on a lent host (issue 29). Device-local memory made and
// freed in blocks of several sizes, and pinned host memory (a tile slot's staging), on one device and then on
// every device at once: does the cost grow with the bytes, and do devices pay it side by side or in turn?
// Usage: memory_probe DEVICE_GB STAGING_GB
// Not part of the build (docs/tiles.md has its figures):
//   g++ -O2 -std=c++20 scripts/memory_probe.cpp -o memory_probe -lvulkan -lpthread
// PROBE_ANY_DEVICE=1 lets it run on lavapipe too (memory_probe 1 1), to check the path, not its speed.
// memory_probe DEVICE_GB STAGING_GB free|exit: instead, that much made on every device at once and then freed
// (free) or left to the process's exit (exit: _exit(0) with every block still made); time the process from
// outside: does leaving the memory to the exit spare the frees' time, or does the exit pay it?
#include <vulkan/vulkan.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

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
  VkPhysicalDeviceMemoryProperties mem{};
  uint32_t local = UINT32_MAX, staging = UINT32_MAX;
};

static uint32_t pick_type(const Dev& d, VkMemoryPropertyFlags want, VkMemoryPropertyFlags avoid) {
  for (uint32_t i = 0; i < d.mem.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags f = d.mem.memoryTypes[i].propertyFlags;
    if ((f & want) == want && !(f & avoid)) return i;
  }
  return UINT32_MAX;
}

// What one device paid: the blocks made, then freed (ms).
struct Cost {
  double make = 0, free = 0;
};

// `bytes` of memory type `type` in blocks of `block`, made then freed; `addressed` as the tiles' pool makes them
// (VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT); `mapped`: each block mapped for its life (the staging).
static Cost make_and_free(const Dev& d, uint32_t type, uint64_t bytes, uint64_t block, bool addressed, bool mapped) {
  std::vector<VkDeviceMemory> blocks;
  Cost c;
  auto t = Clock::now();
  for (uint64_t made = 0; made < bytes; made += block) {
    VkMemoryAllocateFlagsInfo flags{};
    flags.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO;
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{};
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    if (addressed) ai.pNext = &flags;
    ai.allocationSize = std::min(block, bytes - made);
    ai.memoryTypeIndex = type;
    VkDeviceMemory m{};
    CK(vkAllocateMemory(d.dev, &ai, nullptr, &m));
    if (mapped) {
      void* p = nullptr;
      CK(vkMapMemory(d.dev, m, 0, VK_WHOLE_SIZE, 0, &p));
    }
    blocks.push_back(m);
  }
  c.make = ms_since(t);
  t = Clock::now();
  for (VkDeviceMemory m : blocks) {
    if (mapped) vkUnmapMemory(d.dev, m);
    vkFreeMemory(d.dev, m, nullptr);
  }
  c.free = ms_since(t);
  return c;
}

// The same on device 0 alone, then on every device at once (a thread each): per device, and the wall.
static void row(const std::vector<Dev>& devs, const char* what, bool host, uint64_t bytes, uint64_t block,
                bool addressed) {
  const auto one = make_and_free(devs[0], host ? devs[0].staging : devs[0].local, bytes, block, addressed, host);
  std::printf("%-26s block %6.0f MB  one device: make %7.1f ms (%5.1f ms/GB), free %7.1f ms (%5.1f ms/GB)\n", what,
              block / 1e6, one.make, one.make / (bytes / 1e9), one.free, one.free / (bytes / 1e9));
  if (devs.size() < 2) return;
  std::vector<Cost> each(devs.size());
  std::vector<std::thread> threads;
  const auto t = Clock::now();
  for (size_t i = 0; i < devs.size(); ++i)
    threads.emplace_back([&, i] {
      each[i] = make_and_free(devs[i], host ? devs[i].staging : devs[i].local, bytes, block, addressed, host);
    });
  for (auto& th : threads) th.join();
  const double wall = ms_since(t);
  std::printf("%-26s block %6.0f MB  %zu devices at once, wall %7.1f ms:", what, block / 1e6, devs.size(), wall);
  for (const Cost& c : each) std::printf("  make %.0f free %.0f", c.make, c.free);
  std::printf("\n");
  std::fflush(stdout);
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: memory_probe DEVICE_GB STAGING_GB\n");
    return 2;
  }
  const uint64_t device_bytes = uint64_t(std::atof(argv[1]) * 1e9), staging_bytes = uint64_t(std::atof(argv[2]) * 1e9);
  VkApplicationInfo app{};
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ici{};
  ici.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  ici.pApplicationInfo = &app;
  VkInstance inst{};
  CK(vkCreateInstance(&ici, nullptr, &inst));
  uint32_t n = 0;
  CK(vkEnumeratePhysicalDevices(inst, &n, nullptr));
  std::vector<VkPhysicalDevice> phys(n);
  CK(vkEnumeratePhysicalDevices(inst, &n, phys.data()));
  const bool any = std::getenv("PROBE_ANY_DEVICE") != nullptr;
  std::vector<Dev> devs;
  for (VkPhysicalDevice p : phys) {
    VkPhysicalDeviceProperties props;
    vkGetPhysicalDeviceProperties(p, &props);
    if (!any && props.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) continue;
    Dev d;
    d.phys = p;
    vkGetPhysicalDeviceMemoryProperties(p, &d.mem);
    d.local = pick_type(d, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
    d.staging = pick_type(d, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT |
                                 VK_MEMORY_PROPERTY_HOST_CACHED_BIT, 0);
    if (d.staging == UINT32_MAX)
      d.staging = pick_type(d, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT, 0);
    const float prio = 1;
    VkDeviceQueueCreateInfo q{};
    q.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
    q.queueCount = 1;
    q.pQueuePriorities = &prio;
    VkPhysicalDeviceVulkan12Features f12{};
    f12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
    f12.bufferDeviceAddress = VK_TRUE;
    VkDeviceCreateInfo dci{};
    dci.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
    dci.pNext = &f12;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &q;
    CK(vkCreateDevice(p, &dci, nullptr, &d.dev));
    std::printf("device %zu: %s (device-local type %u, staging type %u)\n", devs.size(), props.deviceName, d.local,
                d.staging);
    devs.push_back(d);
  }
  if (devs.empty()) {
    std::fprintf(stderr, "no GPU (PROBE_ANY_DEVICE=1 takes a CPU device)\n");
    return 1;
  }
  const uint64_t mb = 1000000;
  if (argc > 3) {
    const bool leave = std::string(argv[3]) == "exit";
    std::vector<std::thread> threads;
    std::vector<std::vector<VkDeviceMemory>> made(devs.size());
    const auto t = Clock::now();
    for (size_t i = 0; i < devs.size(); ++i)
      threads.emplace_back([&, i] {
        auto make = [&](uint32_t type, uint64_t bytes, uint64_t block, bool mapped) {
          for (uint64_t done = 0; done < bytes; done += block) {
            VkMemoryAllocateInfo ai{};
            ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
            ai.allocationSize = std::min(block, bytes - done);
            ai.memoryTypeIndex = type;
            VkDeviceMemory m{};
            CK(vkAllocateMemory(devs[i].dev, &ai, nullptr, &m));
            void* p = nullptr;
            if (mapped) CK(vkMapMemory(devs[i].dev, m, 0, VK_WHOLE_SIZE, 0, &p));
            made[i].push_back(m);
          }
        };
        make(devs[i].local, device_bytes, 4290 * mb, false);
        make(devs[i].staging, staging_bytes, 3047 * mb, true);
      });
    for (auto& th : threads) th.join();
    threads.clear();
    std::printf("made %.1f + %.1f GB on each of %zu devices in %.0f ms\n", device_bytes / 1e9, staging_bytes / 1e9,
                devs.size(), ms_since(t));
    std::fflush(stdout);
    if (leave) _exit(0);
    const auto f = Clock::now();
    for (size_t i = 0; i < devs.size(); ++i)
      threads.emplace_back([&, i] {
        for (VkDeviceMemory m : made[i]) vkFreeMemory(devs[i].dev, m, nullptr);
        vkDestroyDevice(devs[i].dev, nullptr);
      });
    for (auto& th : threads) th.join();
    std::printf("freed, devices destroyed in %.0f ms\n", ms_since(f));
    std::fflush(stdout);
    vkDestroyInstance(inst, nullptr);
    return 0;
  }
  std::printf("device-local %.1f GB a device, staging %.1f GB a device\n", device_bytes / 1e9, staging_bytes / 1e9);
  for (int round = 0; round < 2; ++round) {
    std::printf("-- round %d\n", round + 1);
    row(devs, "device-local, addressed", false, device_bytes, 4290 * mb, true);
    row(devs, "device-local, addressed", false, device_bytes, 1024 * mb, true);
    row(devs, "device-local, addressed", false, device_bytes, 256 * mb, true);
    row(devs, "device-local, no address", false, device_bytes, 4290 * mb, false);
    row(devs, "staging (pinned, mapped)", true, staging_bytes, 3047 * mb, false);
    row(devs, "staging (pinned, mapped)", true, staging_bytes, 512 * mb, false);
  }
  for (Dev& d : devs) vkDestroyDevice(d.dev, nullptr);
  vkDestroyInstance(inst, nullptr);
}
