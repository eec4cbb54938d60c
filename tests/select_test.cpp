// parallel_select against std::nth_element: large enough for the parallel partition (and, at 40M, for a band
// that is partitioned again), with the rank near the middle, at both ends and outside the sampled band, and with
// keys that tie.
#include "core/select.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <random>
#include <vector>

namespace cdtgpu {
namespace {

std::vector<uint32_t> ids_of(size_t n) {
  std::vector<uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  return ids;
}

// What std::nth_element guarantees: nothing before nth is greater, nothing after it is less.
template <class Less>
void expect_selected(const std::vector<uint32_t>& ids, size_t nth, Less less) {
  for (size_t i = 0; i < nth; ++i) ASSERT_FALSE(less(ids[nth], ids[i])) << "before " << nth << " at " << i;
  for (size_t i = nth + 1; i < ids.size(); ++i) ASSERT_FALSE(less(ids[i], ids[nth])) << "after " << nth << " at " << i;
}

// Ids ordered by key, ties by id: distinct keys, so std::nth_element's id at nth is the only right one.
template <class Key>
auto by_key(const std::vector<Key>& key) {
  return [&key](uint32_t a, uint32_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; };
}

// parallel_select of rank nth among ids 0..n-1: std::nth_element's id there, and every id once.
template <class Less>
void expect_as_nth_element(size_t n, size_t nth, Less less) {
  std::vector<uint32_t> ids = ids_of(n), expected = ids_of(n);
  parallel_select(ids.data(), ids.data() + nth, ids.data() + n, less);
  std::nth_element(expected.begin(), expected.begin() + nth, expected.end(), less);
  EXPECT_EQ(ids[nth], expected[nth]) << "rank " << nth;
  expect_selected(ids, nth, less);
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, ids_of(n)) << "every id once";
}

TEST(ParallelSelect, EqualsNthElementOnDistinctKeys) {
  const size_t n = 3'000'000;
  std::vector<double> key(n);
  std::mt19937_64 rng(7);
  for (double& k : key) k = double(rng() >> 11);
  for (size_t nth : {n / 2, n / 8, size_t(0), n - 1, size_t(12345)}) expect_as_nth_element(n, nth, by_key(key));
}

TEST(ParallelSelect, RankOutsideTheSampledBand) {
  // The ids that parallel_select samples (every n/4096th) get keys in [0, 0.5), all others in [0, 1): the
  // pivots land near the first quartile, the median lies above both, and the part above them (~3/4 of the
  // range) is split again.
  const size_t n = 3'000'000, samples = 4096;
  std::vector<double> key(n);
  std::mt19937_64 rng(5);
  for (double& k : key) k = double(rng() >> 11) * 0x1.0p-53;
  for (size_t i = 0; i < samples; ++i) key[i * n / samples] = 0.5 * double(i) / double(samples);
  expect_as_nth_element(n, n / 2, by_key(key));
}

TEST(ParallelSelect, KeysThatTie) {
  // Three keys (the parts below and above the sampled pivots do not shrink) and one key for all.
  for (uint32_t kinds : {3u, 1u}) {
    const size_t n = 2'000'000;
    auto less = [&](uint32_t a, uint32_t b) { return a % kinds < b % kinds; };
    for (size_t nth : {n / 2, n / 3, n - 2}) {
      std::vector<uint32_t> ids = ids_of(n);
      parallel_select(ids.data(), ids.data() + nth, ids.data() + n, less);
      expect_selected(ids, nth, less);
    }
  }
}

TEST(ParallelSelect, BandPartitionedAgain) {
  // 40M ids: the band between the pivots (~3 %) is over 2^20 ids, so it is partitioned again.
  const size_t n = 40'000'000;
  std::vector<uint32_t> key(n);
  std::mt19937 rng(11);
  for (uint32_t& k : key) k = rng();
  expect_as_nth_element(n, n / 2, by_key(key));
}

}  // namespace
}  // namespace cdtgpu
