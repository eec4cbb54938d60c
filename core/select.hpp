// parallel_select: std::nth_element for ranges of ids, on all cores when the range is large (core/tiles'
// k-d splits of up to 500M vertex ids at 1B points).
//
//   parallel_select(ids.data(), ids.data() + ids.size() / 2, ids.data() + ids.size(), less);
#pragma once
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/parallel.hpp"
#include "core/touched.hpp"

namespace cdtgpu {

// parallel_select's working memory, kept by a caller that selects again (a k-d split's later levels): fresh
// arrays are page faults on every call.
struct SelectScratch {
  RawVector<uint8_t> part;
  RawVector<uint32_t> out;
};

// std::nth_element, on all cores for large ranges: two pivots sampled around the wanted rank split the range
// into below, between and above them (a parallel partition); the rank almost always falls between, and only
// the part that holds it (the band, a few per cent) is selected again in the same way, down to
// std::nth_element. Exact either way.
template <class Less>
void parallel_select(uint32_t* first, uint32_t* nth, uint32_t* last, Less less, SelectScratch* scratch = nullptr) {
  const size_t n = size_t(last - first);
  constexpr size_t kSerial = 1 << 20, kSamples = 4096;
  if (n < kSerial) return std::nth_element(first, nth, last, less);
  std::vector<uint32_t> sample(kSamples);
  for (size_t i = 0; i < kSamples; ++i) sample[i] = first[i * n / kSamples];
  std::sort(sample.begin(), sample.end(), less);
  const size_t rank = size_t(nth - first) * kSamples / n, spread = 64;  // 2 standard deviations (32)
  const uint32_t lo = sample[rank > spread ? rank - spread : 0];
  const uint32_t hi = sample[std::min(kSamples - 1, rank + spread)];
  // Each id's part is kept (a byte), so the points are read once: they are 6x the ids' bytes.
  SelectScratch own;
  SelectScratch& work = scratch ? *scratch : own;
  if (work.part.size() < n) resize_unwritten(work.part, n);
  uint8_t* part = work.part.data();
  constexpr size_t kBlock = 1 << 16;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::array<size_t, 3>> count(blocks + 1, {0, 0, 0});
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      part[i] = uint8_t(!less(first[i], lo)) + uint8_t(!less(first[i], hi));  // no branch: lo < hi
      ++count[b + 1][part[i]];
    }
  });
  std::array<size_t, 3> total{0, 0, 0};
  for (size_t b = 1; b <= blocks; ++b)
    for (int k = 0; k < 3; ++k) total[k] += count[b][k];
  std::array<size_t, 3> at{0, total[0], total[0] + total[1]};
  for (size_t b = 0; b <= blocks; ++b) {  // count[b] becomes block b's write positions
    const std::array<size_t, 3> c = b < blocks ? count[b + 1] : std::array<size_t, 3>{0, 0, 0};
    count[b] = at;
    for (int k = 0; k < 3; ++k) at[k] += c[k];
  }
  if (work.out.size() < n) resize_unwritten(work.out, n);
  uint32_t* out = work.out.data();
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    std::array<size_t, 3> w = count[b];
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) out[w[part[i]]++] = first[i];
  });
  copy_on_all_cores(out, n, first);
  const size_t k = size_t(nth - first);
  uint32_t* from = first + total[0] + total[1];  // the part holding rank k
  uint32_t* to = last;
  if (k < total[0]) from = first, to = first + total[0];
  else if (k < total[0] + total[1]) from = first + total[0], to = first + total[0] + total[1];
  // That part again on all cores: at 1B points a column's bands (31M ids) took ~2 s on one core, the points
  // read in random order. When the rank falls outside the band (one split in twenty), its part is about half
  // the range: 1.2 s on one core at 64M ids. Only a part a sixteenth smaller is split again (equal keys could
  // make one part of all).
  if (size_t(to - from) <= n - n / 16) return parallel_select(from, nth, to, less, &work);
  std::nth_element(from, nth, to, less);
}

}  // namespace cdtgpu
