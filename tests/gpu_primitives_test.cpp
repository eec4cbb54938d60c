// Scan, compaction and radix sort against the CPU (std::exclusive_scan, std::copy_if, std::stable_sort) on
// lengths 0, 1, around block and tile edges, random ones, and a few above 1M. With CDTGPU_LARGE=1 also above
// 16M (for the GPU machine; lavapipe's 128 MiB buffer limit and speed keep those out of CI).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/clock_hold.hpp"
#include "gpu/context.hpp"
#include "gpu/primitives.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

using namespace cdtgpu::gpu;

namespace {

Context& ctx() {
  static Context c = [] {
    ContextOptions options;
    options.validation = true;
    return create_context(options);
  }();
  return c;
}

const Primitives& prims() {
  static Primitives p(ctx());
  return p;
}

bool large() {
  const char* v = std::getenv("CDTGPU_LARGE");
  return v && std::strcmp(v, "1") == 0;
}

// Lengths around the scan block (2048), its square, the radix tile (>= 1024) and some random ones.
std::vector<uint32_t> lengths(uint32_t seed) {
  std::vector<uint32_t> n = {0, 1, 2, 3, 7, 8, 31, 33, 255, 256, 1023, 1024, 1025, 2047, 2048, 2049, 6000};
  std::mt19937 rng(seed);
  for (int i = 0; i < 4; ++i) n.push_back(std::uniform_int_distribution<uint32_t>(3, 300000)(rng));
  n.push_back(1u << 20);             // a power of two above 1M
  n.push_back((1u << 20) + 4099u);   // three scan levels: 2048^2 < n is not needed for that, 513 blocks
  return n;
}

std::vector<uint32_t> random_u32(size_t n, uint32_t seed, uint32_t max) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<uint32_t> d(0, max);
  std::vector<uint32_t> v(n);
  for (auto& x : v) x = d(rng);
  return v;
}

void check_scan(uint32_t n, uint32_t seed, uint32_t max) {
  auto v = random_u32(n, seed, max);
  Buffer in = upload_new(ctx(), v, "in");
  Buffer out = create_buffer(ctx(), uint64_t(n) * 4, "out");
  Recorder rec(ctx());
  prims().exclusive_scan(rec, in, out, n);
  rec.submit();
  std::vector<uint32_t> want(n);
  std::exclusive_scan(v.begin(), v.end(), want.begin(), 0u);
  auto got = download_vector<uint32_t>(ctx(), out, n);
  ASSERT_EQ(got, want) << "n = " << n;
}

// Sorts n keys (key_bits wide) with payload = index and compares with std::stable_sort.
template <class Key>
void check_sort(uint32_t n, uint32_t seed, uint64_t key_mask, uint32_t sort_bits = 0) {
  std::mt19937_64 rng(seed);
  std::vector<Key> keys(n);
  for (auto& k : keys) k = static_cast<Key>(rng() & key_mask);
  std::vector<uint32_t> payload(n);
  std::iota(payload.begin(), payload.end(), 0u);
  Buffer kb = create_buffer(ctx(), uint64_t(n) * sizeof(Key), "keys");
  if (n) upload(ctx(), kb, keys.data(), uint64_t(n) * sizeof(Key));
  Buffer pb = upload_new(ctx(), payload, "payload");
  Recorder rec(ctx());
  prims().radix_sort(rec, kb, pb, n, sizeof(Key) * 8, sort_bits);
  rec.submit();

  std::vector<uint32_t> order = payload;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return keys[a] < keys[b]; });
  std::vector<Key> want_keys(n);
  for (uint32_t i = 0; i < n; ++i) want_keys[i] = keys[order[i]];
  std::vector<Key> got_keys(n);
  if (n) download(ctx(), kb, got_keys.data(), uint64_t(n) * sizeof(Key));
  auto got_payload = download_vector<uint32_t>(ctx(), pb, n);
  ASSERT_EQ(got_keys, want_keys) << "n = " << n;
  ASSERT_EQ(got_payload, order) << "n = " << n << " (stability)";
}

void no_validation_messages() {
  for (auto& m : ctx().messages()) ADD_FAILURE() << m;
  ctx().clear_messages();
}

}  // namespace

TEST(GpuPrimitives, ExclusiveScanMatchesCpu) {
  uint32_t seed = 1;
  for (uint32_t n : lengths(11)) check_scan(n, seed++, 1000);
  check_scan(100000, 5, 0xffffffffu);  // wraps modulo 2^32 like the CPU
  no_validation_messages();
}

TEST(GpuPrimitives, ScanInPlaceAndManyLevels) {
  // 2048^2 + 1 elements: three levels of block sums.
  uint32_t n = 2048u * 2048u + 1u;
  auto v = random_u32(n, 3, 3);
  Buffer b = upload_new(ctx(), v, "data");
  Recorder rec(ctx());
  prims().exclusive_scan(rec, b, b, n);
  rec.submit();
  std::vector<uint32_t> want(n);
  std::exclusive_scan(v.begin(), v.end(), want.begin(), 0u);
  ASSERT_EQ(download_vector<uint32_t>(ctx(), b, n), want);
  no_validation_messages();
}

TEST(GpuPrimitives, CompactionMatchesCpu) {
  uint32_t seed = 100;
  for (uint32_t n : lengths(12)) {
    auto values = random_u32(n, seed++, 0xffffffffu);
    auto flags = random_u32(n, seed++, 3);  // 0 drops; 1, 2, 3 keep: any non-zero flag keeps
    std::vector<uint32_t> want;
    for (uint32_t i = 0; i < n; ++i)
      if (flags[i]) want.push_back(values[i]);
    Buffer vb = upload_new(ctx(), values, "values");
    Buffer fb = upload_new(ctx(), flags, "flags");
    Buffer ob = create_buffer(ctx(), uint64_t(n) * 4, "out");
    uint32_t count = compact_now(prims(), vb, fb, ob, n);
    ASSERT_EQ(count, want.size()) << "n = " << n;
    ASSERT_EQ(download_vector<uint32_t>(ctx(), ob, count), want) << "n = " << n;
  }
  no_validation_messages();
}

TEST(GpuPrimitives, RadixSort32MatchesStableSort) {
  uint32_t seed = 200;
  for (uint32_t n : lengths(13)) {
    check_sort<uint32_t>(n, seed++, 0xffffffffu);
    if (n < 100000) check_sort<uint32_t>(n, seed++, 0xf);  // many equal keys: stability shows
  }
  check_sort<uint32_t>(50000, 7, 0xfff, 12);      // keys below 2^12: 2 passes
  check_sort<uint32_t>(50000, 9, 0xffffff, 24);   // 3 passes (odd): result copied back
  no_validation_messages();
}

TEST(GpuPrimitives, RadixSort64MatchesStableSort) {
  uint32_t seed = 300;
  for (uint32_t n : lengths(14)) {
    check_sort<uint64_t>(n, seed++, ~uint64_t(0));
    if (n < 100000) check_sort<uint64_t>(n, seed++, 0xff000000000000ffull);  // equal low and high bytes
  }
  check_sort<uint64_t>(30000, 8, (uint64_t(1) << 40) - 1, 40);  // 5 passes (odd): result copied back
  no_validation_messages();
}

TEST(GpuPrimitives, SortedAndReversedInputs) {
  for (uint32_t n : {5000u, 70001u}) {
    std::vector<uint32_t> keys(n), payload(n);
    std::iota(keys.begin(), keys.end(), 0u);
    std::iota(payload.begin(), payload.end(), 0u);
    for (int reversed = 0; reversed < 2; ++reversed) {
      std::vector<uint32_t> k = keys;
      if (reversed) std::reverse(k.begin(), k.end());
      Buffer kb = upload_new(ctx(), k, "keys");
      Buffer pb = upload_new(ctx(), payload, "payload");
      Recorder rec(ctx());
      prims().radix_sort(rec, kb, pb, n, 32);
      rec.submit();
      ASSERT_EQ(download_vector<uint32_t>(ctx(), kb, n), keys);
      auto p = download_vector<uint32_t>(ctx(), pb, n);
      ASSERT_EQ(p[0], reversed ? n - 1 : 0u);
      ASSERT_EQ(p[n - 1], reversed ? 0u : n - 1);
    }
  }
  no_validation_messages();
}

// The spins that keep a waiting device's clock up run every step asked for: the first invocation ends where the
// host's chain from the same seed ends. The steps are scaled from each spin's time, so they differ between spins;
// spins asked for a second reach the most a spin takes (lavapipe ends a loop after 65535 turns).
TEST(GpuPrimitives, ClockHoldRunsEveryStep) {
  ClockHold hold(ctx());
  const auto check = [&](int spin) {
    ASSERT_GE(hold.steps(), 1u << 10);
    uint32_t x = hold.seed();
    for (uint32_t i = 0; i < hold.steps(); ++i) x = (x ^ (x >> 15)) * 2246822519u;  // shaders/clock_hold.comp
    EXPECT_EQ(hold.ended_on(), x) << "spin " << spin << " of " << hold.steps() << " steps";
  };
  for (int spin = 0; spin < 3; ++spin) {
    hold.spin(0.5);
    check(spin);
  }
  for (int spin = 3; spin < 20 && hold.steps() < CLOCK_HOLD_MAX; ++spin) {
    hold.spin(1000);
    check(spin);
  }
  EXPECT_EQ(hold.steps(), CLOCK_HOLD_MAX);
}

TEST(GpuPrimitives, LargeInputs) {
  if (!large()) GTEST_SKIP() << "set CDTGPU_LARGE=1 (GPU machine) for inputs above 16M";
  check_scan(20'000'017, 1, 1000);
  check_scan(64u << 20, 2, 7);
  check_sort<uint32_t>(17'000'003, 3, 0xffffffffu);
  check_sort<uint64_t>(17'000'003, 4, ~uint64_t(0));
  no_validation_messages();
}
