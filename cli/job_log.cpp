#include "cli/job_log.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/sink.h>

#include "cli/progress.hpp"

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

// The logger's own sink, with the progress lines cleared before each message.
class ClearingSink : public spdlog::sinks::sink {
 public:
  explicit ClearingSink(spdlog::sink_ptr inner) : inner_(std::move(inner)) {}
  void log(const spdlog::details::log_msg& msg) override {
    Progress::clear_lines();
    inner_->log(msg);
  }
  void flush() override { inner_->flush(); }
  void set_pattern(const std::string& pattern) override { inner_->set_pattern(pattern); }
  void set_formatter(std::unique_ptr<spdlog::formatter> f) override { inner_->set_formatter(std::move(f)); }

 private:
  spdlog::sink_ptr inner_;
};

}  // namespace

JobLogScope::JobLogScope(const std::string& job) : previous_(std::move(current_job)) { current_job = job; }
JobLogScope::~JobLogScope() { current_job = std::move(previous_); }

void use_job_log(spdlog::logger& logger) {
  for (spdlog::sink_ptr& s : logger.sinks()) s = std::make_shared<ClearingSink>(s);
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<JobFlag>('J').set_pattern("cdtgpu: %^%l%$: %J%v");
  logger.set_formatter(std::move(formatter));
}

}  // namespace cdtgpu
