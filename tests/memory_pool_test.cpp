// The device memory pool (gpu/memory_pool.hpp; the tiles reserve one per device): first-fit ranges that merge
// when given back, and buffers taken from a reserved pool that hold their data apart from each other, holes
// reused, addressed buffers too, the rest allocated as before.
#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/memory_pool.hpp"
#include "tests/gpu_test_context.hpp"

using namespace cdtgpu;
using namespace cdtgpu::gpu;
using cdtgpu::test::ctx;

namespace {

uint32_t device_type() {
  for (uint32_t i = 0; i < ctx().memory.memoryTypeCount; ++i)
    if (ctx().memory.memoryTypes[i].propertyFlags & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) return i;
  return 0;
}

}  // namespace

TEST(MemoryPool, FirstFitAlignsAndMergesWhatIsGivenBack) {
  MemoryPool pool(ctx(), 1 << 20, device_type());
  const auto a = pool.take(1000, 256), b = pool.take(3000, 256), c = pool.take(100, 4096);
  ASSERT_TRUE(a && b && c);
  EXPECT_EQ(*a, 0u);
  EXPECT_EQ(*b, 1024u);  // 1000 rounded up to the alignment
  EXPECT_EQ(*c, 4096u);
  EXPECT_EQ(pool.free_bytes(), (1u << 20) - 1000 - 3000 - 100);
  EXPECT_FALSE(pool.take(1 << 20, 256));  // larger than what is free
  pool.give(*b, 3000);
  const auto d = pool.take(2000, 256);  // the hole b left, first fit
  ASSERT_TRUE(d);
  EXPECT_EQ(*d, 1024u);
  pool.give(*a, 1000);
  pool.give(*d, 2000);
  pool.give(*c, 100);
  EXPECT_EQ(pool.free_bytes(), 1u << 20);
  const auto whole = pool.take(1 << 20, 1);  // everything merged back into one range
  ASSERT_TRUE(whole);
  EXPECT_EQ(*whole, 0u);
  cdtgpu::test::no_validation_messages();
}

TEST(MemoryPool, BuffersFromAReservedPoolKeepTheirData) {
  reserve_device_pool(ctx(), 4 << 20);
  auto pattern = [](uint32_t seed, size_t n) {
    std::vector<uint32_t> v(n);
    std::iota(v.begin(), v.end(), seed * 1000003u);
    return v;
  };
  std::vector<Buffer> buffers;
  std::vector<size_t> sizes = {1000, 70000, 3, 250000, 12345, 1000000};  // words; the last does not fit
  for (size_t i = 0; i < sizes.size(); ++i) {
    buffers.push_back(create_buffer(ctx(), sizes[i] * 4, "pool test"));
    upload(ctx(), buffers[i], pattern(uint32_t(i), sizes[i]).data(), sizes[i] * 4);
  }
  EXPECT_TRUE(buffers[0].pool) << "the first buffer should come from the pool";
  EXPECT_FALSE(buffers[5].pool) << "a buffer beyond the pool gets memory of its own";
  buffers[1] = Buffer();  // a hole, taken again below
  buffers[1] = create_buffer(ctx(), 50000 * 4, "pool test");
  sizes[1] = 50000;
  upload(ctx(), buffers[1], pattern(99, sizes[1]).data(), sizes[1] * 4);
  EXPECT_TRUE(buffers[1].pool);
  // An addressed buffer (bound by its device address) from the pool: its address lies in the pool's memory.
  Buffer addressed = create_addressed_buffer(ctx(), 4096, "pool test addressed");
  EXPECT_TRUE(addressed.pool);
  EXPECT_NE(addressed.address, 0u);
  for (size_t i = 0; i < sizes.size(); ++i) {
    std::vector<uint32_t> got(sizes[i]);
    download(ctx(), buffers[i], got.data(), sizes[i] * 4);
    EXPECT_EQ(got, pattern(i == 1 ? 99 : uint32_t(i), sizes[i])) << "buffer " << i;
  }
  cdtgpu::test::no_validation_messages();
}
