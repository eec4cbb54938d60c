// Parallel primitives on uint32 data: exclusive prefix sum, stream compaction and a stable LSD radix sort of
// 32/64-bit keys with a uint32 payload. Each call records dispatches into a Recorder; scratch comes from
// Recorder::temp. Results do not depend on the subgroup size.
#pragma once
#include <cstdint>

#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/recorder.hpp"

namespace cdtgpu::gpu {

// Caller-owned second arrays for Primitives::radix_sort (null: temporary buffers).
struct SortScratch {
  const Buffer* keys = nullptr;
  const Buffer* payload = nullptr;
};

struct Primitives {
  explicit Primitives(const Context& ctx);

  // out[i] = in[0] + ... + in[i-1] (mod 2^32) for i < n; `out` may be `in`. Cost: ~2 reads + 1 write per element.
  void exclusive_scan(Recorder& rec, const Buffer& in, const Buffer& out, uint32_t n) const;
  // After an exclusive scan of n > 0 counts has run: the sum of all of them (the last offset plus the last
  // count), read back, so the caller can size what the scan lays out.
  uint64_t scanned_total(const Buffer& offsets, const Buffer& counts, uint32_t n) const;
  // Keeps values[i] where flags[i] != 0, in order, at out[0..count); writes count to count_out[0].
  void compact(Recorder& rec, const Buffer& values, const Buffer& flags, const Buffer& out, const Buffer& count_out,
               uint32_t n) const;
  // Stable sort of n (key, payload) pairs in place by key, 8 bits per pass (deterministic: no atomics decide
  // positions). key_bits = 32: keys are uint32; 64: keys are uint64 (little-endian words). When every key is
  // below 2^sort_bits, passing sort_bits saves the passes over the zero high digits (0 means key_bits).
  // The second key and payload arrays come from rec.temp() unless the caller passes its own (`scratch`: n keys,
  // n payloads at least).
  void radix_sort(Recorder& rec, const Buffer& keys, const Buffer& payload, uint32_t n, uint32_t key_bits,
                  uint32_t sort_bits = 0, SortScratch scratch = SortScratch()) const;

  const Context& ctx;
  Pass scan_block, scan_add, compact_scatter, radix_histogram, radix_scatter;
};

// Runs compact() now and returns the count.
uint32_t compact_now(const Primitives& prims, const Buffer& values, const Buffer& flags, const Buffer& out,
                     uint32_t n);

}  // namespace cdtgpu::gpu
