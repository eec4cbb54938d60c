// The Vulkan context: instance (optionally with the Khronos validation layer), the chosen physical device, a
// logical device with one compute queue and a command pool (and a copy queue with its own pool where the device
// has one: Context::copy_queue). Also lists what the loader sees, for `cdtgpu devices`.
//
//   gpu::ContextOptions options;  options.validation = true;
//   gpu::Context ctx = gpu::create_context(options);
//   ... record and submit work (see passes.hpp) ...
//   EXPECT_TRUE(ctx.messages().empty());   // validation messages, when validation is on
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cdtgpu::gpu {

class DeviceMemoryPool;

// One physical device as the loader reports it.
struct DeviceInfo {
  uint32_t index = 0;                 // position in vkEnumeratePhysicalDevices
  std::string name;
  std::string type;                   // "discrete", "integrated", "virtual", "cpu", "other"
  std::string driver_name;            // VkPhysicalDeviceDriverProperties
  std::string driver_info;
  uint32_t api_version = 0;
  std::vector<uint64_t> heap_sizes;   // bytes, one per memory heap
  std::vector<bool> heap_device_local;
  bool float64 = false;               // shaderFloat64
  bool int64 = false;                 // shaderInt64
  bool int64_atomics = false;         // shaderBufferInt64Atomics
  bool timestamps = false;            // compute queue has timestampValidBits > 0
  bool subgroup_ops = false;          // basic + arithmetic + ballot subgroup ops in compute shaders
  bool push_descriptors = false;      // VK_KHR_push_descriptor
  bool buffer_address = false;        // bufferDeviceAddress (the triangle buffers, shaders/tri_refs.glsl)
  uint64_t max_storage_buffer_range = 0;
  uint32_t subgroup_size = 0;
  uint32_t max_shared_memory = 0;     // maxComputeSharedMemorySize
  float timestamp_period = 0;         // ns per timestamp tick
  std::string missing;                // what the pipeline needs and this device lacks; empty = usable
};

struct ContextOptions {
  // Device override: a decimal index into the list, or a case-insensitive substring of the name.
  // Empty: the first usable discrete GPU, then integrated, then virtual, then CPU (lavapipe).
  std::string device;
  // Enable VK_LAYER_KHRONOS_validation when it is installed. The env var CDTGPU_VALIDATION=1 turns it on as
  // well (and then a missing layer is an error).
  bool validation = false;
  // Throw DeviceError instead of creating a device on a CPU Vulkan driver (lavapipe): `--backend auto` runs the
  // CGAL backend there, which is faster.
  bool hardware_only = false;
  // Host-visible staging memory to reserve for upload() and download() (gpu/buffers.hpp), pinned on a thread
  // of its own beside the command pool and the pipeline cache; its milliseconds into *staging_ms when given.
  uint64_t staging_bytes = 0;
  double* staging_ms = nullptr;
  // Device memory made ahead for the run's buffers (gpu/device_memory_pool.hpp), on a thread of its own beside
  // the staging; 0: none. None under CDTGPU_DEVICE_MEMORY_LIMIT either.
  uint64_t device_pool_bytes = 0;
  // An MPI rank's own GPU, where `device` is empty: the (nth_gpu mod n)-th of the host's n GPUs as
  // select_devices(..., "all") lists them; -1: pick_device's. Chosen here, from the start's own device list,
  // so that the rank does not list them first (0.15-0.25 s on the 2 x H200 host, before its GPU started).
  int nth_gpu = -1;
  // The processes taking the host's GPUs that way: more than the GPUs, and they share some (Context::shared),
  // so no device memory is made ahead.
  int processes_on_host = 1;
};

// Lists every physical device the loader sees (the first call creates and destroys an instance of its own; later
// calls give the same list).
std::vector<DeviceInfo> list_devices();
// Index into `devices` of the device the options would pick; throws DeviceError when none fits.
size_t pick_device(const std::vector<DeviceInfo>& devices, const std::string& override_name);
// Human-readable listing for `cdtgpu devices`: one block per device, the picked one marked.
std::string describe_devices(const std::string& override_name = "");
// True when VK_LAYER_KHRONOS_validation is installed.
bool validation_layer_available();

// Owns the Vulkan objects; move-only, destroyed in reverse order. Fields are plain so passes and buffers can
// use them directly.
// Device memory the buffers of one context hold, against an optional cap: CDTGPU_DEVICE_MEMORY_LIMIT (bytes, or
// with a K, M or G suffix) limits what the GPU backend may allocate, as a smaller device would.
struct MemoryBudget {
  uint64_t limit = 0;  // 0: no cap
  std::atomic<uint64_t> used{0};
};
// The cap from the environment: 0 when unset; DeviceError when it is not a byte count.
uint64_t device_memory_limit_from_env();

struct Context {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queue_family = 0;
  VkCommandPool pool = VK_NULL_HANDLE;  // RESET_COMMAND_BUFFER: recorders reset and reuse their buffers
  // A queue for copies beside the compute queue's work, with a command pool of its own: a tile's points go up and
  // another's triangles come down while a third computes (gpu/tile_triangulator). A transfer-only family's (the
  // copy engines; every buffer is then shared by both families), else a second queue of the compute family; null
  // where neither exists (lavapipe): those copies then take the compute queue. CDTGPU_COPY_QUEUE=compute or =none
  // asks for the second compute queue or none.
  VkQueue copy_queue = VK_NULL_HANDLE;
  uint32_t copy_family = 0;
  VkCommandPool copy_pool = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties props{};
  VkPhysicalDeviceMemoryProperties memory{};
  DeviceInfo info;
  bool shared = false;                  // other processes may take this GPU too (ContextOptions::nth_gpu)
  bool validation = false;              // the validation layer is active
  PFN_vkCmdPushDescriptorSetKHR cmd_push_descriptor_set = nullptr;
  // CDTGPU_SHADER_STATS=1 and VK_KHR_pipeline_executable_properties: create_pass prints each pipeline's
  // statistics (registers, spills: what limits occupancy) to stderr.
  bool shader_stats = false;
  // Pipelines are created through this cache, seeded from and saved to disk (gpu/pipeline_cache.hpp).
  VkPipelineCache pipeline_cache = VK_NULL_HANDLE;
  std::string pipeline_cache_file;   // empty: not kept on disk
  size_t pipeline_cache_loaded = 0;  // bytes of driver data the run started with
  uint64_t pipeline_cache_hash = 0;  // of that data: saved again only when it changed

  // Every validation warning or error recorded since creation (or the last clear_messages()).
  const std::vector<std::string>& messages() const { return *messages_; }
  void clear_messages() { messages_->clear(); }

  Context() = default;
  Context(Context&& o) noexcept;
  Context& operator=(Context&& o) noexcept;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context();

  std::unique_ptr<std::vector<std::string>> messages_ = std::make_unique<std::vector<std::string>>();
  // The host-visible staging buffer upload() and download() reuse (gpu/buffers.cpp; grown as needed, freed
  // before the device): allocating and pinning host memory for every copy cost more than the copy itself.
  mutable std::shared_ptr<void> staging;
  // Small scratch buffers Recorder::temp() hands out and takes back at submit (gpu/recorder.cpp): the constraint
  // rounds' scans made ~60 allocations per triangulation, each a driver call.
  mutable std::shared_ptr<void> temp_pool;
  // Device-local bytes its buffers hold, and the cap (shared: a buffer gives its bytes back when it is freed).
  std::shared_ptr<MemoryBudget> memory_budget = std::make_shared<MemoryBudget>();
  // Where device buffers take their memory first (ContextOptions::device_pool_bytes, or made later by a tiled
  // run's first reserve, gpu/tile_triangulator, while other threads make buffers: hence atomic); null: none.
  mutable std::atomic<std::shared_ptr<DeviceMemoryPool>> memory_pool;
};

// Saves the context's pipeline cache to its file when the run compiled something new (destroying the context
// does this too).
void store_pipeline_cache(const Context& ctx);

// Creates the context; throws DeviceError (naming the device and the missing features) when the chosen device
// cannot run the pipeline: it needs shaderFloat64, shaderInt64, shaderBufferInt64Atomics, timestamps, subgroup
// arithmetic/ballot and VK_KHR_push_descriptor.
Context create_context(const ContextOptions& options = {});

}  // namespace cdtgpu::gpu
