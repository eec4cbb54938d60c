#include "cli/progress.hpp"

#include <unistd.h>

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

namespace cdtgpu {

Progress::Progress(std::string stage) : stage_(std::move(stage)) {
  if (!::isatty(STDERR_FILENO) || !spdlog::should_log(spdlog::level::info)) return;
  thread_ = std::thread([this] {
    using namespace std::chrono;
    const auto t0 = steady_clock::now();
    bool shown = false;
    std::unique_lock lock(mutex_);
    for (auto wake = t0 + seconds(1); !done_cv_.wait_until(lock, wake, [&] { return done_; });
         wake += milliseconds(250)) {
      std::fprintf(stderr, "\rcdtgpu: %s... %.1f s", stage_.c_str(),
                   duration<double>(steady_clock::now() - t0).count());
      std::fflush(stderr);
      shown = true;
    }
    if (shown) std::fputs("\r\033[K", stderr);  // erase the line: the log says what the stage took
  });
}

void Progress::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  done_cv_.notify_one();
  thread_.join();
}

}  // namespace cdtgpu
