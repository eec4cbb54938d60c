// A progress line on stderr for a stage that runs longer than a second, while stderr is a terminal and the
// log level shows info (so never in pipes, logs or with -q). The line is cleared when the stage ends.
#pragma once
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace cdtgpu {

class Progress {
 public:
  explicit Progress(std::string stage);
  ~Progress() { stop(); }
  // Ends the line (clears it) before anything else is logged.
  void stop();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

 private:
  std::string stage_;
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::thread thread_;
};

}  // namespace cdtgpu
