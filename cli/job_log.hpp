// Which job a thread works on, named at the start of its log lines: a batch runs several jobs at once on its
// stage threads, and "line 7: merged 3 duplicate points" must say whose points.
//
//   use_job_log_pattern(*logger);        // once: "cdtgpu: LEVEL: [JOB: ]MESSAGE"
//   { JobLogScope scope("line 7"); spdlog::info("..."); }   // "cdtgpu: info: line 7: ..."
#pragma once
#include <string>

#include <spdlog/logger.h>

namespace cdtgpu {

class JobLogScope {
 public:
  explicit JobLogScope(const std::string& job);  // empty: no prefix
  ~JobLogScope();
  JobLogScope(const JobLogScope&) = delete;
  JobLogScope& operator=(const JobLogScope&) = delete;

 private:
  std::string previous_;
};

void use_job_log_pattern(spdlog::logger& logger);

}  // namespace cdtgpu
