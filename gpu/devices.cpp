#include "gpu/devices.hpp"

#include <algorithm>
#include <exception>
#include <sstream>
#include <thread>

#include "gpu/check.hpp"

namespace cdtgpu::gpu {

std::vector<size_t> select_devices(const std::vector<DeviceInfo>& devices, const std::string& spec,
                                   const std::string& single, bool repeats) {
  if (spec.empty()) return {pick_device(devices, single)};
  std::vector<size_t> picked;
  if (spec == "all") {
    for (const char* type : {"discrete", "integrated"})
      for (size_t i = 0; i < devices.size(); ++i)
        if (devices[i].type == type && devices[i].missing.empty()) picked.push_back(i);
    if (picked.empty()) picked.push_back(pick_device(devices, ""));  // lavapipe or a virtual device: one
    std::sort(picked.begin(), picked.end());
    return picked;
  }
  std::stringstream list(spec);
  for (std::string item; std::getline(list, item, ',');) {
    if (item.empty() || !std::all_of(item.begin(), item.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw DeviceError("--devices takes all or device indices separated by commas (as `cdtgpu devices` lists "
                        "them), not '" + spec + "'");
    const size_t i = pick_device(devices, item);  // range and features checked, with its message
    if (!repeats && std::find(picked.begin(), picked.end(), i) != picked.end())
      throw DeviceError("--devices names device " + item + " twice");
    picked.push_back(i);
  }
  std::sort(picked.begin(), picked.end());
  return picked;
}

std::vector<std::unique_ptr<Context>> create_contexts(const std::vector<size_t>& indices, ContextOptions options) {
  std::vector<std::unique_ptr<Context>> contexts(indices.size());
  std::vector<std::exception_ptr> errors(indices.size());
  std::vector<std::thread> starts;
  for (size_t k = 0; k < indices.size(); ++k)
    starts.emplace_back([&, k, options]() mutable {
      try {
        options.device = std::to_string(indices[k]);
        contexts[k] = std::make_unique<Context>(create_context(options));
      } catch (...) {
        errors[k] = std::current_exception();
      }
    });
  for (std::thread& t : starts) t.join();
  for (size_t k = 0; k < indices.size(); ++k)
    if (errors[k]) {
      try {
        std::rethrow_exception(errors[k]);
      } catch (const std::exception& e) {
        throw DeviceError("device " + std::to_string(indices[k]) + ": " + e.what());
      }
    }
  return contexts;
}

}  // namespace cdtgpu::gpu
