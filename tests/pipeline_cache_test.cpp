// The pipeline cache on disk (gpu/pipeline_cache.hpp): written after a run, read by the next, and any file that
// is missing, damaged or from another device, driver or build is ignored, never fatal.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "gpu/cdt_pipeline.hpp"
#include "gpu/context.hpp"
#include "gpu/pipeline_cache.hpp"

using namespace cdtgpu;
namespace fs = std::filesystem;

namespace {

std::vector<char> slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void spit(const std::string& p, const std::vector<char>& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
}

VkPhysicalDeviceProperties fake_device() {
  VkPhysicalDeviceProperties p{};
  p.vendorID = 0x10de;
  p.deviceID = 0x2330;
  p.driverVersion = 42;
  for (unsigned i = 0; i < VK_UUID_SIZE; ++i) p.pipelineCacheUUID[i] = uint8_t(i);
  return p;
}

class PipelineCache : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("cdtgpu_pc_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const char* old = std::getenv("XDG_CACHE_HOME");
    saved = old ? old : "";
    had = old != nullptr;
    ::setenv("XDG_CACHE_HOME", dir.c_str(), 1);
    // Mesa keeps its own shader cache under XDG_CACHE_HOME too: a warm one of its own keeps lavapipe's
    // compiles (seconds each) out of this test; ours is what is tested.
    if (!std::getenv("MESA_SHADER_CACHE_DIR")) {
      ::setenv("MESA_SHADER_CACHE_DIR", (fs::temp_directory_path() / "cdtgpu_test_mesa_cache").c_str(), 1);
      set_mesa = true;
    }
  }
  void TearDown() override {
    if (had)
      ::setenv("XDG_CACHE_HOME", saved.c_str(), 1);
    else
      ::unsetenv("XDG_CACHE_HOME");
    if (set_mesa) ::unsetenv("MESA_SHADER_CACHE_DIR");
    fs::remove_all(dir);
  }
  fs::path dir;
  std::string saved;
  bool had = false, set_mesa = false;
};

}  // namespace

TEST_F(PipelineCache, RoundTripsAndRejectsWhatDoesNotMatch) {
  const VkPhysicalDeviceProperties dev = fake_device();
  const std::string path = gpu::pipeline_cache_path(dev);
  ASSERT_EQ(path.rfind(dir.string(), 0), 0u) << path;
  EXPECT_TRUE(gpu::load_pipeline_cache(path, dev).empty());  // missing
  const std::vector<char> payload{'d', 'r', 'i', 'v', 'e', 'r', ' ', 'd', 'a', 't', 'a'};
  ASSERT_TRUE(gpu::save_pipeline_cache(path, dev, payload));
  EXPECT_EQ(gpu::load_pipeline_cache(path, dev), payload);

  VkPhysicalDeviceProperties other = dev;  // another GPU of the same driver
  other.deviceID = 0x2331;
  EXPECT_TRUE(gpu::load_pipeline_cache(path, other).empty());
  other = dev;  // a driver update
  other.driverVersion = 43;
  EXPECT_TRUE(gpu::load_pipeline_cache(path, other).empty());
  other = dev;
  other.pipelineCacheUUID[3] ^= 1;
  EXPECT_TRUE(gpu::load_pipeline_cache(path, other).empty());

  const std::vector<char> good = slurp(path);
  std::vector<char> bad = good;
  bad[bad.size() - 1] = char(bad[bad.size() - 1] ^ 0x40);  // one flipped bit in the driver's data
  spit(path, bad);
  EXPECT_TRUE(gpu::load_pipeline_cache(path, dev).empty());
  spit(path, std::vector<char>(good.begin(), good.begin() + long(good.size()) - 3));  // truncated
  EXPECT_TRUE(gpu::load_pipeline_cache(path, dev).empty());
  spit(path, std::vector<char>(good.begin(), good.begin() + 10));  // shorter than the header
  EXPECT_TRUE(gpu::load_pipeline_cache(path, dev).empty());
  spit(path, {});
  EXPECT_TRUE(gpu::load_pipeline_cache(path, dev).empty());
}

TEST_F(PipelineCache, ARealContextWritesItAndAGarbageFileChangesNothing) {
  std::string path;
  {
    gpu::Context ctx = gpu::create_context();
    path = ctx.pipeline_cache_file;
    ASSERT_FALSE(path.empty());
    EXPECT_EQ(ctx.pipeline_cache_loaded, 0u);
    gpu::GpuCdt cdt(ctx);  // creates (compiles) every pipeline
  }
  ASSERT_TRUE(fs::exists(path));
  {
    gpu::Context ctx = gpu::create_context();
    EXPECT_GT(ctx.pipeline_cache_loaded, 0u);
  }
  // Garbage where the cache was: ignored, the context works, and the file is replaced by a good one.
  spit(path, std::vector<char>(4096, '\x5a'));
  {
    gpu::Context ctx = gpu::create_context();
    EXPECT_EQ(ctx.pipeline_cache_loaded, 0u);
    gpu::GpuCdt cdt(ctx);
    PreparedInput p;
    p.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
    EXPECT_EQ(cdt.triangulate(p).mesh.triangles.size(), 2u);
  }
  EXPECT_FALSE(gpu::load_pipeline_cache(path, [&] {
                 gpu::Context ctx = gpu::create_context();
                 return ctx.props;
               }()).empty());
}
