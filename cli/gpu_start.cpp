#include "cli/gpu_start.hpp"

#include <cstdlib>
#include <filesystem>

namespace cdtgpu {

uint64_t auto_min_points() {
  if (const char* v = std::getenv("CDTGPU_AUTO_MIN_POINTS"); v && *v) return std::strtoull(v, nullptr, 10);
  return kAutoMinPoints;
}

uint64_t input_bytes(const std::vector<std::string>& paths) {
  uint64_t total = 0;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (p == "-" || !std::filesystem::is_regular_file(p, ec)) continue;
    total += std::filesystem::file_size(p, ec);
  }
  return total;
}

GpuStart::GpuStart(const std::string& device, bool hardware_only) {
  pending_ = std::async(std::launch::async, [device, hardware_only] {
    auto r = std::make_unique<Ready>();
    gpu::ContextOptions options;
    options.device = device;
    options.hardware_only = hardware_only;
    r->ctx = gpu::create_context(options);
    r->cdt = std::make_unique<gpu::GpuCdt>(r->ctx);  // queues every pipeline's compile
    return r;
  });
}

GpuStart::~GpuStart() {
  if (pending_.valid()) pending_.wait();
  if (ready_) ready_->cdt.reset();  // its passes before the context
}

gpu::GpuCdt& GpuStart::cdt() {
  if (!ready_) ready_ = pending_.get();
  return *ready_->cdt;
}

const gpu::Context& GpuStart::context() {
  cdt();
  return ready_->ctx;
}

}  // namespace cdtgpu
