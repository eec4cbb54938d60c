#include "cli/gpu_start.hpp"

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>

namespace cdtgpu {

uint64_t auto_min_points() {
  if (const char* v = std::getenv("CDTGPU_AUTO_MIN_POINTS"); v && *v) return std::strtoull(v, nullptr, 10);
  return kAutoMinPoints;
}

uint64_t max_input_points(const std::vector<std::string>& paths) {
  uint64_t total = 0;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (p == "-" || !std::filesystem::is_regular_file(p, ec)) continue;
    std::string ext = std::filesystem::path(p).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    const uint64_t bytes_per_point = ext == ".asc" ? 2 : ext == ".shp" ? 28 : 6;
    total += std::filesystem::file_size(p, ec) / bytes_per_point;
  }
  return total;
}

GpuStart::GpuStart(const std::string& device, bool hardware_only) {
  pending_ = std::async(std::launch::async, [this, device, hardware_only] {
    using Clock = std::chrono::steady_clock;
    auto ms = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
    auto r = std::make_unique<Ready>();
    gpu::ContextOptions options;
    options.device = device;
    options.hardware_only = hardware_only;
    auto t = Clock::now();
    r->ctx = gpu::create_context(options);
    context_ms = ms(t);
    t = Clock::now();
    r->cdt = std::make_unique<gpu::GpuCdt>(r->ctx);  // queues every pipeline's compile
    pipelines_ms = ms(t);
    return r;
  });
}

GpuStart::~GpuStart() {
  if (pending_.valid()) pending_.wait();
  if (ready_) ready_->cdt.reset();  // its passes before the context
}

void GpuStart::leave_for_exit() {
  if (pending_.valid()) {
    try {
      ready_ = pending_.get();
    } catch (...) {  // a start that failed has nothing to leave
      return;
    }
  }
  if (!ready_) return;
  gpu::store_pipeline_cache(ready_->ctx);
  (void)ready_.release();  // deliberately never destroyed
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
