// DevicePool: indices (devices, or the staging slots of gpu/tile_triangulator) taken by one thread at a time,
// waiting while none is free. No Vulkan in it.
//
//   DevicePool slots(2 * devices);
//   const size_t slot = slots.take_spread(devices);  // slot % devices: the tile's device
//   const DevicePool::Held held{slots, slot};       // given back at the end of the scope
#pragma once
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

namespace cdtgpu::gpu {

class DevicePool {
 public:
  explicit DevicePool(size_t n) {
    for (size_t i = n; i-- > 0;) free_.push_back(i);
  }
  // The last one given back (the lowest at first).
  size_t take() {
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty(); });
    const size_t i = free_.back();
    free_.pop_back();
    return i;
  }
  // For slots of `devices` devices (slot i is device i % devices'): a free slot of the device with the most
  // free ones; among those, of the device given a slot longest ago (its tile ends first), then the lowest.
  // A tile's slot fixes its device, which may still be busy with another tile: take() sent a run's first
  // tiles to busy devices while one stood idle for 350 ms (1B points on 4), and the lowest slot alone gave
  // device 0 five of 16 tiles and device 3 three.
  size_t take_spread(size_t devices) {
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty(); });
    std::vector<size_t> free_of(devices, 0);
    for (size_t i : free_) ++free_of[i % devices];
    given_at_.resize(devices, 0);
    auto better = [&](size_t a, size_t b) {
      const size_t da = a % devices, db = b % devices;
      if (free_of[da] != free_of[db]) return free_of[da] > free_of[db];
      if (given_at_[da] != given_at_[db]) return given_at_[da] < given_at_[db];
      return a < b;
    };
    const auto at = std::min_element(free_.begin(), free_.end(), better);
    const size_t i = *at;
    free_.erase(at);
    given_at_[i % devices] = ++given_;
    return i;
  }
  // Waits for i.
  void take(size_t i) {
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return std::find(free_.begin(), free_.end(), i) != free_.end(); });
    free_.erase(std::find(free_.begin(), free_.end(), i));
  }
  // Takes i if it is free now.
  bool try_take(size_t i) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto at = std::find(free_.begin(), free_.end(), i);
    if (at == free_.end()) return false;
    free_.erase(at);
    return true;
  }
  // Gives i back when it goes out of scope.
  struct Held {
    DevicePool& pool;
    size_t i;
    ~Held() { pool.give(i); }
  };

  void give(size_t i) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(i);
    }
    freed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable freed_;
  std::vector<size_t> free_;
  std::vector<uint64_t> given_at_;  // take_spread: when each device was last given a slot (0: never)
  uint64_t given_ = 0;
};

}  // namespace cdtgpu::gpu
