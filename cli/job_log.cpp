#include "cli/job_log.hpp"

#include <spdlog/pattern_formatter.h>

namespace cdtgpu {
namespace {

thread_local std::string current_job;

// %J: "JOB: " while a JobLogScope is open on the logging thread, else nothing.
class JobFlag : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg&, const std::tm&, spdlog::memory_buf_t& dest) override {
    if (current_job.empty()) return;
    dest.append(current_job.data(), current_job.data() + current_job.size());
    dest.append(std::string_view(": "));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<JobFlag>(); }
};

}  // namespace

JobLogScope::JobLogScope(const std::string& job) : previous_(std::move(current_job)) { current_job = job; }
JobLogScope::~JobLogScope() { current_job = std::move(previous_); }

void use_job_log_pattern(spdlog::logger& logger) {
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<JobFlag>('J').set_pattern("cdtgpu: %^%l%$: %J%v");
  logger.set_formatter(std::move(formatter));
}

}  // namespace cdtgpu
