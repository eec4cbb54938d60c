// A progress line on stderr for work that runs longer than a second, while stderr is a terminal and the log
// level shows info (so never in pipes, logs or with -q). The line is cleared when the work ends.
#pragma once
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace cdtgpu {

class Progress {
 public:
  // "cdtgpu: STAGE... 2.5 s"
  explicit Progress(std::string stage);
  // "cdtgpu: TEXT()" (called about four times a second; the caller keeps what it reads thread-safe).
  explicit Progress(std::function<std::string()> text);
  ~Progress() { stop(); }
  // Ends the line (clears it) before anything else is logged.
  void stop();
  // Clears every progress line shown now, so that a log message stands on a line of its own (the redraw comes
  // with the next tick). cli/job_log's sink calls it before each message.
  static void clear_lines();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

 private:
  std::function<std::string()> text_;
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false, shown_ = false;
  std::thread thread_;
};

}  // namespace cdtgpu
