// Scan, compaction and radix sort; see primitives.hpp. The shaders hold the algorithms, this file the levels.
#include "gpu/primitives.hpp"

#include <algorithm>

#include "gpu/check.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

Primitives::Primitives(const Context& context)
    : ctx(context),
      scan_block(create_pass(ctx, {"scan_block", 3, sizeof(ScanPush)})),
      scan_add(create_pass(ctx, {"scan_add", 2, sizeof(ScanAddPush)})),
      compact_scatter(create_pass(ctx, {"compact_scatter", 5, sizeof(CompactPush)})),
      radix_histogram(create_pass(ctx, {"radix_histogram", 2, sizeof(RadixPush)})),
      radix_scatter(create_pass(ctx, {"radix_scatter", 5, sizeof(RadixPush)})) {}

namespace {

uint64_t div_up(uint64_t a, uint64_t b) { return (a + b - 1) / b; }

// Scan of n elements, blocks of SCAN_BLOCK; block totals are scanned recursively (2048^k elements at level k).
void scan_levels(const Primitives& pr, Recorder& rec, const Buffer& in, const Buffer& out, uint32_t n,
                 bool binarize) {
  if (n == 0) return;
  uint32_t blocks = static_cast<uint32_t>(div_up(n, SCAN_BLOCK));
  const Buffer& sums = rec.temp(blocks * sizeof(uint32_t), "scan block sums");
  ScanPush push{n, blocks > 1 ? 1u : 0u, binarize ? 1u : 0u};
  rec.dispatch_groups(pr.scan_block, {in, out, sums}, push, blocks);
  if (blocks == 1) return;
  scan_levels(pr, rec, sums, sums, blocks, false);
  rec.dispatch_groups(pr.scan_add, {out, sums}, ScanAddPush{n}, blocks);
}

}  // namespace

void Primitives::exclusive_scan(Recorder& rec, const Buffer& in, const Buffer& out, uint32_t n) const {
  scan_levels(*this, rec, in, out, n, false);
}

void Primitives::compact(Recorder& rec, const Buffer& values, const Buffer& flags, const Buffer& out,
                         const Buffer& count_out, uint32_t n) const {
  if (n == 0) {
    rec.fill(count_out, 0);
    return;
  }
  const Buffer& offsets = rec.temp(uint64_t(n) * sizeof(uint32_t), "compact offsets");
  scan_levels(*this, rec, flags, offsets, n, true);
  rec.dispatch_groups(compact_scatter, {values, flags, offsets, out, count_out}, CompactPush{n},
                      div_up(n, COMPACT_WG));
}

uint64_t Primitives::scanned_total(const Buffer& offsets, const Buffer& counts, uint32_t n) const {
  uint32_t last[2] = {0, 0};
  download(ctx, offsets, &last[0], 4, uint64_t(n - 1) * 4);
  download(ctx, counts, &last[1], 4, uint64_t(n - 1) * 4);
  return uint64_t(last[0]) + last[1];
}

void Primitives::radix_sort(Recorder& rec, const Buffer& keys, const Buffer& payload, uint32_t n, uint32_t key_bits,
                            uint32_t sort_bits, SortScratch scratch) const {
  if (key_bits != 32 && key_bits != 64)
    throw DeviceError("radix_sort: key_bits must be 32 or 64, got " + std::to_string(key_bits));
  if (sort_bits == 0) sort_bits = key_bits;
  if (sort_bits > key_bits) throw DeviceError("radix_sort: sort_bits > key_bits");
  if (n <= 1) return;
  uint32_t words = key_bits / 32;
  uint32_t sg = ctx.info.subgroup_size;
  // A tile of at least 1024 keys keeps the histogram (256 counts per tile) at most a quarter of the keys.
  uint32_t tile_size = std::max(1024u, sg * RADIX_ITEMS);
  uint32_t num_tiles = static_cast<uint32_t>(div_up(n, tile_size));
  uint32_t tiles_per_group = RADIX_WG / sg;
  uint64_t groups = div_up(num_tiles, tiles_per_group);

  const Buffer& keys2 = scratch.keys ? *scratch.keys : rec.temp(uint64_t(n) * words * sizeof(uint32_t), "radix keys");
  const Buffer& values2 = scratch.payload ? *scratch.payload : rec.temp(uint64_t(n) * sizeof(uint32_t), "radix payload");
  const Buffer& hist = rec.temp(uint64_t(num_tiles) * RADIX_BINS * sizeof(uint32_t), "radix histogram");
  const Buffer* src_k = &keys;
  const Buffer* src_v = &payload;
  const Buffer* dst_k = &keys2;
  const Buffer* dst_v = &values2;
  uint32_t passes = (sort_bits + 7) / 8;
  for (uint32_t pass = 0; pass < passes; ++pass) {
    RadixPush push{n, pass * 8, words == 2 ? 1u : 0u, num_tiles, tile_size};
    rec.dispatch_groups(radix_histogram, {*src_k, hist}, push, groups);
    scan_levels(*this, rec, hist, hist, num_tiles * RADIX_BINS, false);
    rec.dispatch_groups(radix_scatter, {*src_k, *src_v, *dst_k, *dst_v, hist}, push, groups);
    std::swap(src_k, dst_k);
    std::swap(src_v, dst_v);
  }
  if (src_k != &keys) {  // odd number of passes: the result is in the scratch pair
    rec.copy(*src_k, keys, uint64_t(n) * words * sizeof(uint32_t));
    rec.copy(*src_v, payload, uint64_t(n) * sizeof(uint32_t));
  }
}

uint32_t compact_now(const Primitives& prims, const Buffer& values, const Buffer& flags, const Buffer& out,
                     uint32_t n) {
  Buffer count = create_buffer(prims.ctx, sizeof(uint32_t), "compact count");
  Recorder rec(prims.ctx);
  prims.compact(rec, values, flags, out, count, n);
  rec.submit();
  uint32_t c = 0;
  download(prims.ctx, count, &c, sizeof(c));
  return c;
}

}  // namespace cdtgpu::gpu
