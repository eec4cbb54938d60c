// Timestamp queries around named stages; see profiler.hpp.
#include "gpu/profiler.hpp"

#include "gpu/check.hpp"

namespace cdtgpu::gpu {

Profiler::Profiler(const Context& ctx, uint32_t max_stages) : ctx_(ctx), capacity_(max_stages) {
  VkQueryPoolCreateInfo qi{};
  qi.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
  qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
  qi.queryCount = 2 * max_stages;
  VK_CHECK(vkCreateQueryPool(ctx.device, &qi, nullptr, &pool_));
}

Profiler::~Profiler() { vkDestroyQueryPool(ctx_.device, pool_, nullptr); }

void Profiler::begin(Recorder& rec, const std::string& name) {
  if (names_.size() >= capacity_)
    throw DeviceError("profiler: more than " + std::to_string(capacity_) + " stages (at '" + name + "')");
  rec.barrier();  // begins the command buffer; also keeps earlier work out of this stage's time
  if (!reset_recorded_) {
    vkCmdResetQueryPool(rec.cmd(), pool_, 0, 2 * capacity_);
    reset_recorded_ = true;
  }
  uint32_t id = static_cast<uint32_t>(names_.size());
  names_.push_back(name);
  closed_.push_back(false);
  open_.push_back(id);
  vkCmdWriteTimestamp(rec.cmd(), VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, pool_, 2 * id);
}

void Profiler::end(Recorder& rec) {
  if (open_.empty()) throw DeviceError("profiler: end() without begin()");
  uint32_t id = open_.back();
  open_.pop_back();
  rec.barrier();  // the stage's last dispatch has finished before the end stamp
  vkCmdWriteTimestamp(rec.cmd(), VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, 2 * id + 1);
  closed_[id] = true;
}

std::vector<StageTime> Profiler::results() const {
  std::vector<StageTime> out;
  if (names_.empty()) return out;
  std::vector<uint64_t> ticks(2 * names_.size());
  VK_CHECK(vkGetQueryPoolResults(ctx_.device, pool_, 0, static_cast<uint32_t>(ticks.size()),
                                 ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                 VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  for (size_t i = 0; i < names_.size(); ++i) {
    if (!closed_[i]) throw DeviceError("profiler: stage '" + names_[i] + "' was not ended");
    double dt = static_cast<double>(ticks[2 * i + 1] - ticks[2 * i]);
    out.push_back({names_[i], dt * ctx_.info.timestamp_period * 1e-6});
  }
  return out;
}

void Profiler::reset() {
  names_.clear();
  open_.clear();
  closed_.clear();
  reset_recorded_ = false;
}

}  // namespace cdtgpu::gpu
