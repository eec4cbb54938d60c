// What a run reports with --stats: counts, CRS and time per stage.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace cdtgpu {

struct RunStats {
  nlohmann::ordered_json counts = nlohmann::ordered_json::object();
  std::string crs;
  int crs_epsg = 0;  // 0: none known
  std::string backend;         // the backend that ran: gpu or cgal
  std::string backend_reason;  // why (auto's choice, or the flag)
  std::string device;  // the Vulkan device, for the gpu backend
  uint64_t peak_host_bytes = 0;  // the process's peak resident memory (0: not measured)
  std::vector<std::pair<std::string, double>> stage_ms;  // in run order
  nlohmann::ordered_json gpu_stage_ms = nlohmann::ordered_json::object();  // device timestamps, if any

  nlohmann::ordered_json to_json() const {
    nlohmann::ordered_json j;
    j["counts"] = counts;
    j["crs"] = crs;
    if (crs_epsg) j["crs_epsg"] = crs_epsg;
    j["backend"] = backend;
    if (!backend_reason.empty()) j["backend_reason"] = backend_reason;
    if (!device.empty()) j["device"] = device;
    if (peak_host_bytes) j["peak_host_bytes"] = peak_host_bytes;
    nlohmann::ordered_json s = nlohmann::ordered_json::object();
    for (const auto& [k, v] : stage_ms) s[k] = v;
    j["stage_ms"] = s;
    if (!gpu_stage_ms.empty()) j["gpu_stage_ms"] = gpu_stage_ms;
    return j;
  }
};

}  // namespace cdtgpu
