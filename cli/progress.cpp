#include "cli/progress.hpp"

#include <unistd.h>

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

namespace cdtgpu {
namespace {

std::mutex drawing_mutex;
std::vector<Progress*> drawing;  // the lines with a drawing thread

}  // namespace

Progress::Progress(std::string stage)
    : Progress([stage, t0 = std::chrono::steady_clock::now()] {
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, "... %.1f s",
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        return stage + seconds;
      }) {}

Progress::Progress(std::function<std::string()> text) : text_(std::move(text)) {
  if (!::isatty(STDERR_FILENO) || !spdlog::should_log(spdlog::level::info)) return;
  {
    std::lock_guard lock(drawing_mutex);
    drawing.push_back(this);
  }
  thread_ = std::thread([this] {
    using namespace std::chrono;
    std::unique_lock lock(mutex_);
    for (auto wake = steady_clock::now() + seconds(1); !done_cv_.wait_until(lock, wake, [&] { return done_; });
         wake += milliseconds(250)) {
      std::fprintf(stderr, "\r\033[Kcdtgpu: %s", text_().c_str());
      std::fflush(stderr);
      shown_ = true;
    }
    if (shown_) std::fputs("\r\033[K", stderr);  // erase the line: the log says what the work took
  });
}

void Progress::clear_lines() {
  std::lock_guard all(drawing_mutex);
  for (Progress* p : drawing) {
    std::lock_guard lock(p->mutex_);
    if (!p->shown_) continue;
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    p->shown_ = false;
  }
}

void Progress::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard lock(drawing_mutex);
    std::erase(drawing, this);
  }
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  done_cv_.notify_one();
  thread_.join();
}

}  // namespace cdtgpu
