// DevicePool (gpu/device_pool.hpp): take_spread gives each tile a slot of the device with the fewest tiles,
// whatever order the slots came back in; take gives the last one back.
#include "gpu/device_pool.hpp"

#include <gtest/gtest.h>

#include <future>
#include <thread>
#include <vector>

namespace cdtgpu::gpu {
namespace {

TEST(DevicePool, SpreadTakesTheDeviceWithTheMostFreeSlots) {
  DevicePool slots(8);  // 4 devices, 2 slots each: slot i is device i % 4's
  std::vector<size_t> taken;
  for (int k = 0; k < 4; ++k) taken.push_back(slots.take_spread(4));
  EXPECT_EQ(taken, (std::vector<size_t>{0, 1, 2, 3}));  // one tile a device before a second on any
  // Back in another order, as a run's tiles end: still one a device first, the lowest slot of each.
  for (size_t i : {3, 1, 2, 0}) slots.give(i);
  taken.clear();
  for (int k = 0; k < 4; ++k) taken.push_back(slots.take_spread(4) % 4);
  EXPECT_EQ(taken, (std::vector<size_t>{0, 1, 2, 3}));
  // Devices 0, 1 and 2 hold a tile each (both of device 3's slots free): the next goes to device 3.
  slots.give(3);
  EXPECT_EQ(slots.take_spread(4) % 4, 3u);
}

TEST(DevicePool, SpreadTakesInTurnWhileEveryDeviceHoldsATile) {
  DevicePool slots(8);
  for (int k = 0; k < 4; ++k) slots.take_spread(4);  // a tile on each device, in turn
  slots.give(1);
  EXPECT_EQ(slots.take_spread(4) % 4, 1u);  // device 1's tile ended: its next is given at once
  // Each device holds one tile and has one slot free: the next tiles go to the devices given one longest ago,
  // whose tiles end first (device 1 last: it was just given one), not to the lowest slot first.
  std::vector<size_t> devices;
  for (int k = 0; k < 4; ++k) devices.push_back(slots.take_spread(4) % 4);
  EXPECT_EQ(devices, (std::vector<size_t>{0, 2, 3, 1}));
}

TEST(DevicePool, TakeGivesTheLastOneBack) {
  DevicePool slots(8);
  std::vector<size_t> taken;
  for (int k = 0; k < 8; ++k) taken.push_back(slots.take());
  EXPECT_EQ(taken, (std::vector<size_t>{0, 1, 2, 3, 4, 5, 6, 7}));
  for (size_t i : {7, 3}) slots.give(i);
  EXPECT_EQ(slots.take(), 3u);
  EXPECT_EQ(slots.take_spread(4), 7u);
}

TEST(DevicePool, WaitsUntilOneIsGivenBack) {
  DevicePool slots(2);
  const size_t a = slots.take_spread(1), b = slots.take_spread(1);
  auto third = std::async(std::launch::async, [&] { return slots.take_spread(1); });
  EXPECT_EQ(third.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
  slots.give(b);
  EXPECT_EQ(third.get(), b);
  slots.give(a);
}

TEST(DevicePool, TryTakeTakesOnlyAFreeOne) {
  DevicePool devices(2);
  devices.take(1);
  EXPECT_FALSE(devices.try_take(1));
  EXPECT_TRUE(devices.try_take(0));
  EXPECT_FALSE(devices.try_take(0));
  devices.give(1);
  EXPECT_TRUE(devices.try_take(1));
}

}  // namespace
}  // namespace cdtgpu::gpu
