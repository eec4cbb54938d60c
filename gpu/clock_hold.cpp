#include "gpu/clock_hold.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "gpu/recorder.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

ClockHold::ClockHold(const Context& ctx)
    : ctx_(ctx),
      pass_(create_pass(ctx, {"clock_hold", 1, sizeof(layout::ClockHoldPush)})),
      sink_(create_buffer(ctx, CLOCK_HOLD_WG * sizeof(uint32_t), "clock hold")) {
  pass_.handle();
}

void ClockHold::spin(double ms) {
  steps_ = next_steps_;
  ++seed_;
  const auto t0 = std::chrono::steady_clock::now();
  Recorder rec(ctx_);
  rec.dispatch(pass_, {sink_}, layout::ClockHoldPush{steps_, seed_}, 1);
  rec.submit();
  const double took = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  // The fastest rate seen: a spin that waited for the driver (another thread pinning memory: the steps shrank to
  // 4743 and the clock fell) or for the pipeline's compile is no measure of the device. At most 4x more a spin.
  steps_per_ms_ = std::max(steps_per_ms_, steps_ / std::max(took, 1e-3));
  next_steps_ = uint32_t(std::clamp(std::llround(std::min(steps_per_ms_ * ms, 4.0 * steps_)), 1ll << 10,
                                    (long long)CLOCK_HOLD_MAX));
}

uint32_t ClockHold::ended_on() const { return download_vector<uint32_t>(ctx_, sink_, 1)[0]; }

}  // namespace cdtgpu::gpu
