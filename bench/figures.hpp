// What every bench table computes and prints: milliseconds since a moment, the median of runs, a table cell.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/timing.hpp"

namespace cdtgpu::figures {

using Clock = std::chrono::steady_clock;

using cdtgpu::ms_since;

// NaN when there are no runs.
inline double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

// `decimals` below 100, none from 100 up; "-" for NaN.
inline std::string fmt(double v, int decimals = 1) {
  if (std::isnan(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", v < 100 ? decimals : 0, v);
  return buf;
}

}  // namespace cdtgpu::figures
