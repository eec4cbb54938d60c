// Which job a thread works on, named at the start of its log lines: a batch runs several jobs at once on its
// stage threads, and "line 7: merged 3 duplicate points" must say whose points.
//
//   use_job_log(*logger);                // once: "cdtgpu: LEVEL: [JOB: ]MESSAGE", progress lines cleared first
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

// Sets the pattern, and has each message clear the progress lines on the terminal first (cli/progress.hpp).
void use_job_log(spdlog::logger& logger);

}  // namespace cdtgpu
