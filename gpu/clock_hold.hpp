// Keeps a device's clock up while it waits for the host. An H200 left idle for ~0.8 s lowers its SM clock from
// 1980 MHz towards 345, and is back at full clock only ~200 ms into the next work: the first tile of a CLI run,
// which comes after the host's prepare, ran at about half clock (docs/tiles.md, session 67). A spin keeps one
// workgroup busy for about the time asked: the device counts as working, and it takes one SM and no memory.
#pragma once
#include <cstdint>

#include "gpu/buffers.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"

namespace cdtgpu::gpu {

class ClockHold {
 public:
  // Waits for the spin's pipeline, so that no spin holds the device while it compiles.
  explicit ClockHold(const Context& ctx);

  // One spin of about `ms` on the device's queue, waited for (the driver's wait sleeps): its steps from the
  // fastest rate of the spins so far. The caller holds the device.
  void spin(double ms);

  uint32_t steps() const { return steps_; }  // the last spin's steps
  uint32_t seed() const { return seed_; }    // and its seed
  // Where the last spin's first invocation ended (a download): a test checks that every step ran.
  uint32_t ended_on() const;

 private:
  const Context& ctx_;
  Pass pass_;
  Buffer sink_;
  uint32_t steps_ = 0;
  uint32_t next_steps_ = 1u << 16;  // ~0.15 ms on an H200 at full clock; the first spins find the rate
  uint32_t seed_ = 0;
  double steps_per_ms_ = 0;
};

}  // namespace cdtgpu::gpu
