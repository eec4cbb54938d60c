// Milliseconds since a moment on the steady clock: stage times, and the -v lines that report them.
#pragma once
#include <chrono>
#include <cstdio>
#include <string>

namespace cdtgpu {

inline double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// A -v line's steps, each with its milliseconds: add("name") as each step ends; text() is "name 1.2, other 3.4".
class StepTimes {
 public:
  void add(const char* what) {
    char ms[32];
    std::snprintf(ms, sizeof ms, " %.1f", ms_since(t_));
    text_ += (text_.empty() ? "" : ", ") + std::string(what) + ms;
    t_ = std::chrono::steady_clock::now();
  }
  const std::string& text() const { return text_; }

 private:
  std::chrono::steady_clock::time_point t_ = std::chrono::steady_clock::now();
  std::string text_;
};

}  // namespace cdtgpu
