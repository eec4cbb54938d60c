// GPU timestamps around named stages of a recording; results in milliseconds (ticks * timestampPeriod).
//
//   gpu::Profiler prof(ctx);
//   prof.begin(rec, "scan"); prims.exclusive_scan(rec, in, out, n); prof.end(rec);
//   rec.submit();
//   for (auto& s : prof.results()) stats[s.name] = s.ms;
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>
#include <vector>

#include "gpu/context.hpp"
#include "gpu/recorder.hpp"

namespace cdtgpu::gpu {

struct StageTime {
  std::string name;
  double ms = 0;
};

class Profiler {
 public:
  explicit Profiler(const Context& ctx, uint32_t max_stages = 128);
  ~Profiler();
  Profiler(const Profiler&) = delete;
  Profiler& operator=(const Profiler&) = delete;

  // Stages may nest; end() closes the innermost open one. The first begin() after construction or reset()
  // records the query-pool reset into `rec`, so all stages of one round must be in submissions that run after it.
  void begin(Recorder& rec, const std::string& name);
  void end(Recorder& rec);
  // After the recording was submitted: every stage in begin order (waits for the queries).
  std::vector<StageTime> results() const;
  // Forget the stages; the next begin() starts a new round.
  void reset();

 private:
  const Context& ctx_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t capacity_ = 0;
  std::vector<std::string> names_;
  std::vector<uint32_t> open_;  // indices of stages begun and not ended
  std::vector<bool> closed_;
  bool reset_recorded_ = false;
};

}  // namespace cdtgpu::gpu
