// The Vulkan context: device listing and choice, validation that really records misuse and stays silent on a
// clean run, buffer limits, VK_CHECK messages, pass/recorder argument checks and the profiler.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "gpu/devices.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"
#include "shaders/layout_cdt.h"
#include "shaders/layout_dt.h"

using namespace cdtgpu::gpu;

namespace {

Context& shared_context() {
  static Context ctx = [] {
    ContextOptions options;
    options.validation = true;
    return create_context(options);
  }();
  return ctx;
}

DeviceInfo fake(const std::string& name, const std::string& type, const std::string& missing) {
  DeviceInfo d;
  d.name = name;
  d.type = type;
  d.missing = missing;
  return d;
}

}  // namespace

TEST(GpuContext, ListsDevicesWithTheirProperties) {
  auto devices = list_devices();
  ASSERT_FALSE(devices.empty());
  for (size_t i = 0; i < devices.size(); ++i) {
    EXPECT_EQ(devices[i].index, i);
    EXPECT_FALSE(devices[i].name.empty());
    EXPECT_FALSE(devices[i].heap_sizes.empty());
    EXPECT_GT(devices[i].max_storage_buffer_range, 0u);
    EXPECT_GT(devices[i].subgroup_size, 0u);
  }
  std::string text = describe_devices();
  size_t picked = pick_device(devices, "");
  EXPECT_NE(text.find(devices[picked].name), std::string::npos);
  EXPECT_NE(text.find("picked: " + std::to_string(picked)), std::string::npos) << text;
  EXPECT_NE(text.find("maxStorageBufferRange"), std::string::npos);
}

TEST(GpuContext, PicksDiscreteThenIntegratedThenCpu) {
  std::vector<DeviceInfo> d = {fake("llvmpipe", "cpu", ""), fake("Some iGPU", "integrated", ""),
                               fake("Big GPU", "discrete", "")};
  EXPECT_EQ(pick_device(d, ""), 2u);
  d[2].missing = "shaderFloat64";  // a discrete GPU without float64 is passed over
  EXPECT_EQ(pick_device(d, ""), 1u);
  d[1].missing = "shaderBufferInt64Atomics";
  EXPECT_EQ(pick_device(d, ""), 0u);
  d[0].missing = "timestamps on the compute queue";
  try {
    pick_device(d, "");
    FAIL() << "no usable device must throw";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("Big GPU' lacks shaderFloat64"), std::string::npos) << e.what();
  }
}

TEST(GpuContext, OverrideByIndexOrNameAndRefusal) {
  std::vector<DeviceInfo> d = {fake("llvmpipe (LLVM 15)", "cpu", ""), fake("NVIDIA H100", "discrete", "")};
  EXPECT_EQ(pick_device(d, "0"), 0u);
  EXPECT_EQ(pick_device(d, "LLVMpipe"), 0u);
  EXPECT_EQ(pick_device(d, "h100"), 1u);
  EXPECT_THROW(pick_device(d, "7"), DeviceError);
  EXPECT_THROW(pick_device(d, "radeon"), DeviceError);
  d[1].missing = "shaderFloat64";
  try {
    pick_device(d, "h100");
    FAIL() << "a device without shaderFloat64 must be refused";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("lacks shaderFloat64"), std::string::npos) << e.what();
  }
  // The real devices: overriding by the picked device's own name gives that device.
  auto real = list_devices();
  size_t p = pick_device(real, "");
  EXPECT_EQ(pick_device(real, real[p].name), p);
  EXPECT_EQ(pick_device(real, std::to_string(p)), p);
}

// An MPI rank's GPU (ContextOptions::nth_gpu): the host's nth in select_devices' order, wrapping; shared, and
// then without device memory made ahead, when more processes than GPUs take them; --device still wins.
TEST(GpuContext, ARanksGpuIsTheHostsNthAndSharedBeyondTheirCount) {
  const std::vector<size_t> gpus = select_devices(list_devices(), "all");
  const int n = int(gpus.size());
  for (int nth : {0, n - 1, n, 2 * n + 1}) {
    for (int processes : {n, n + 1}) {
      ContextOptions o;
      o.nth_gpu = nth;
      o.processes_on_host = processes;
      o.device_pool_bytes = 16 << 20;
      Context ctx = create_context(o);
      EXPECT_EQ(ctx.info.index, gpus[size_t(nth % n)]) << nth;
      EXPECT_EQ(ctx.shared, processes > n) << processes;
      if (!std::getenv("CDTGPU_DEVICE_MEMORY_LIMIT")) {
        EXPECT_EQ(ctx.memory_pool.load() != nullptr, processes <= n) << processes;
      }
    }
  }
  ContextOptions o;
  o.device = std::to_string(gpus.back());
  o.nth_gpu = 0;
  o.processes_on_host = n + 1;
  const Context ctx = create_context(o);
  EXPECT_EQ(ctx.info.index, gpus.back());
  EXPECT_FALSE(ctx.shared);
}

TEST(GpuContext, ValidationRecordsMisuse) {
  if (!validation_layer_available()) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation not installed";
  Context& ctx = shared_context();
  ASSERT_TRUE(ctx.validation);
  ctx.clear_messages();
  // usage = 0 is invalid (VUID-VkBufferCreateInfo-usage-requiredbitmask) and harmless to the driver.
  VkBufferCreateInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bi.size = 64;
  bi.usage = 0;
  VkBuffer b = VK_NULL_HANDLE;
  if (vkCreateBuffer(ctx.device, &bi, nullptr, &b) == VK_SUCCESS) vkDestroyBuffer(ctx.device, b, nullptr);
  EXPECT_FALSE(ctx.messages().empty());
  ctx.clear_messages();
}

TEST(GpuContext, ValidationCleanRun) {
  Context& ctx = shared_context();
  ctx.clear_messages();
  {
    Primitives prims(ctx);
    std::vector<uint32_t> v(5000);
    std::iota(v.begin(), v.end(), 1u);
    Buffer in = upload_new(ctx, v, "in");
    Buffer out = create_buffer(ctx, v.size() * 4, "out");
    Buffer payload = upload_new(ctx, v, "payload");
    Recorder rec(ctx);
    Profiler prof(ctx);
    prof.begin(rec, "scan");
    prims.exclusive_scan(rec, in, out, uint32_t(v.size()));
    prof.end(rec);
    prof.begin(rec, "sort");
    prims.radix_sort(rec, in, payload, uint32_t(v.size()), 32);
    prof.end(rec);
    rec.submit();
    auto times = prof.results();
    ASSERT_EQ(times.size(), 2u);
    EXPECT_EQ(times[0].name, "scan");
    EXPECT_GE(times[0].ms, 0.0);
    EXPECT_GE(times[1].ms, 0.0);
    auto r = download_vector<uint32_t>(ctx, out, v.size());
    EXPECT_EQ(r[4999], 4999u * 5000u / 2u);
    // The recorder can be reused after submit.
    rec.fill(out, 7);
    rec.submit();
    EXPECT_EQ(download_vector<uint32_t>(ctx, out, 3), (std::vector<uint32_t>{7, 7, 7}));
  }
  for (auto& m : ctx.messages()) ADD_FAILURE() << m;
}

TEST(GpuContext, OversizedBufferIsRefusedNamingTheLimit) {
  Context& ctx = shared_context();
  uint64_t limit = ctx.info.max_storage_buffer_range;
  try {
    create_buffer(ctx, limit + 4, "points");
    FAIL() << "a buffer over maxStorageBufferRange must be refused";
  } catch (const DeviceError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find("maxStorageBufferRange"), std::string::npos) << m;
    EXPECT_NE(m.find(std::to_string(limit)), std::string::npos) << m;
    EXPECT_NE(m.find("points"), std::string::npos) << m;
  }
}

TEST(GpuContext, BuffersRoundTripFillAndZeroSize) {
  Context& ctx = shared_context();
  ctx.clear_messages();
  std::vector<uint32_t> v = {1, 2, 3, 0xdeadbeef, 5};
  Buffer b = upload_new(ctx, v, "b");
  EXPECT_EQ(download_vector<uint32_t>(ctx, b, v.size()), v);
  uint32_t x = 42;
  upload(ctx, b, &x, 4, 8);
  EXPECT_EQ(download_vector<uint32_t>(ctx, b, 5), (std::vector<uint32_t>{1, 2, 42, 0xdeadbeef, 5}));
  fill(ctx, b, 9);
  EXPECT_EQ(download_vector<uint32_t>(ctx, b, 5), std::vector<uint32_t>(5, 9));
  EXPECT_THROW(upload(ctx, b, v.data(), 8, 16), DeviceError);  // past the end
  Buffer empty = create_buffer(ctx, 0, "empty");
  EXPECT_EQ(empty.size, 0u);
  EXPECT_TRUE(download_vector<uint32_t>(ctx, empty, 0).empty());
  for (auto& m : ctx.messages()) ADD_FAILURE() << m;
}

// The copy queue: a transfer-only family's where the device has one, else a second compute queue, else none
// (the copies then take the compute queue). Copies through staging on it either way, with no validation
// message.
TEST(GpuContext, CopyQueueWhereTheDeviceHasOne) {
  Context& ctx = shared_context();
  ctx.clear_messages();
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical, &n, fams.data());
  bool transfer_only = false;
  for (const auto& f : fams)
    transfer_only |=
        (f.queueFlags & VK_QUEUE_TRANSFER_BIT) && !(f.queueFlags & (VK_QUEUE_COMPUTE_BIT | VK_QUEUE_GRAPHICS_BIT));
  const bool expected = transfer_only || fams[ctx.queue_family].queueCount > 1;
  EXPECT_EQ(ctx.copy_queue != VK_NULL_HANDLE, expected);
  EXPECT_EQ(ctx.copy_pool != VK_NULL_HANDLE, expected);
  if (transfer_only) {
    EXPECT_NE(ctx.copy_family, ctx.queue_family);
  }
  std::vector<uint32_t> v(1000);
  std::iota(v.begin(), v.end(), 7u);
  HostStaging staging;
  staging.fit(ctx, v.size() * 4);
  std::copy(v.begin(), v.end(), static_cast<uint32_t*>(staging.mapped));
  Buffer b = create_buffer(ctx, v.size() * 4, "b");
  copy_from_staging(ctx, staging, b, v.size() * 4, Queue::copy);
  EXPECT_EQ(download_vector<uint32_t>(ctx, b, v.size()), v);  // written on the copy queue, read on the other
  fill(ctx, b, 3);
  copy_to_staging(ctx, b, staging, v.size() * 4, Queue::copy);
  const uint32_t* back = static_cast<const uint32_t*>(staging.mapped);
  EXPECT_EQ(std::vector<uint32_t>(back, back + v.size()), std::vector<uint32_t>(v.size(), 3));
  for (auto& m : ctx.messages()) ADD_FAILURE() << m;
}

TEST(GpuContext, CopyQueueCanBeTurnedOffOrRefusesAnUnknownChoice) {
  setenv("CDTGPU_COPY_QUEUE", "none", 1);
  {
    const Context ctx = create_context();
    EXPECT_EQ(ctx.copy_queue, VK_NULL_HANDLE);
    EXPECT_EQ(ctx.copy_pool, VK_NULL_HANDLE);
  }
  setenv("CDTGPU_COPY_QUEUE", "engines", 1);
  EXPECT_THROW(create_context(), DeviceError);
  unsetenv("CDTGPU_COPY_QUEUE");
}

TEST(GpuContext, VkCheckNamesCallFileAndSpecialErrors) {
  auto fails = [](VkResult r) { VK_CHECK(r); };
  try {
    fails(VK_ERROR_DEVICE_LOST);
    FAIL();
  } catch (const VulkanError& e) {
    std::string m = e.what();
    EXPECT_EQ(e.result, VK_ERROR_DEVICE_LOST);
    EXPECT_NE(m.find("device lost"), std::string::npos) << m;
    EXPECT_NE(m.find("Vulkan call r failed"), std::string::npos) << m;
    EXPECT_NE(m.find("gpu_context_test.cpp:"), std::string::npos) << m;
  }
  try {
    fails(VK_ERROR_OUT_OF_DEVICE_MEMORY);
    FAIL();
  } catch (const VulkanError& e) {
    EXPECT_NE(std::string(e.what()).find("out of GPU memory"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(fails(VK_SUCCESS));
}

TEST(GpuContext, PassesAreEmbeddedAndArgumentsChecked) {
  Context& ctx = shared_context();
  ctx.clear_messages();
  auto names = shader_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "scan_block"), names.end());
  EXPECT_GT(shader_spirv("scan_block").size(), 5u);
  EXPECT_EQ(shader_spirv("scan_block")[0], 0x07230203u);  // SPIR-V magic
  EXPECT_THROW(shader_spirv("no_such_shader"), DeviceError);
  Pass add = create_pass(ctx, {"scan_add", 2, sizeof(cdtgpu::gpu::layout::ScanAddPush)});
  Buffer a = create_buffer(ctx, 16, "a");
  Recorder rec(ctx);
  EXPECT_THROW(rec.dispatch_groups(add, {a}, cdtgpu::gpu::layout::ScanAddPush{4}, 1), DeviceError);  // 1 buffer of 2
  EXPECT_THROW(rec.dispatch_groups(add, {a, a}, uint64_t{4}, 1), DeviceError);  // wrong push size
  rec.submit();
  for (auto& m : ctx.messages()) ADD_FAILURE() << m;
}

TEST(GpuContext, AddressBindingsAreReadFromTheShaderAndChecked) {
  // The triangle buffers are bound by device address (shaders/tri_refs.glsl): which bindings take one comes
  // from the SPIR-V, and a plain buffer there (or an addressed one elsewhere) is refused before it is bound.
  Context& ctx = shared_context();
  ctx.clear_messages();
  EXPECT_EQ(create_pass(ctx, {"dt_flip", 9, sizeof(cdtgpu::gpu::layout::DtFlipPush)}).addressed, 0b11u);
  EXPECT_EQ(create_pass(ctx, {"canonical_place", 4, sizeof(cdtgpu::gpu::layout::CanonicalKeysPush)}).addressed,
            0b1001u);
  EXPECT_EQ(create_pass(ctx, {"scan_add", 2, sizeof(cdtgpu::gpu::layout::ScanAddPush)}).addressed, 0u);
  Pass map = create_pass(ctx, {"cdt_vertex_map", 2, sizeof(cdtgpu::gpu::layout::CdtSlotsPush)});
  Buffer verts = create_addressed_buffer(ctx, 12, "tri_verts");
  Buffer plain = create_buffer(ctx, 16, "vmap");
  EXPECT_NE(verts.address, 0u);
  EXPECT_EQ(plain.address, 0u);
  const cdtgpu::gpu::layout::CdtSlotsPush push{1, 0, 0};
  Recorder rec(ctx);
  try {
    rec.dispatch_groups(map, {plain, plain}, push, 1);
    ADD_FAILURE() << "a plain buffer where the shader takes an address must be refused";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("binding 0 takes a buffer address"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rec.dispatch_groups(map, {verts, verts}, push, 1), DeviceError);
  // Bound right, the pass reads the slot's corners through the address: vmap[v] = the slot (0) for each.
  const uint32_t tri[3] = {2, 0, 1};
  upload(ctx, verts, tri, sizeof tri);
  fill(ctx, plain, 0xFFFFFFFFu);
  rec.dispatch_groups(map, {verts, plain}, push, 1);
  rec.submit();
  EXPECT_EQ(download_vector<uint32_t>(ctx, plain, 4), (std::vector<uint32_t>{0, 0, 0, 0xFFFFFFFFu}));
  for (auto& m : ctx.messages()) ADD_FAILURE() << m;
}
