#include "cli/batch_devices.hpp"

#include <algorithm>
#include <map>
#include <sstream>

#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "gpu/devices.hpp"

namespace cdtgpu {

std::vector<DeviceWorker> batch_device_workers(const std::string& spec, const std::string& device) {
  const std::vector<gpu::DeviceInfo> devices = gpu::list_devices();
  const size_t picked = gpu::pick_device(devices, device);
  std::vector<size_t> indices;
  if (!device.empty() || spec.empty()) {
    indices = {picked};
  } else if (spec == "all") {
    indices = gpu::select_devices(devices, "all");
  } else {
    std::stringstream list(spec);
    for (std::string item; std::getline(list, item, ',');) {
      if (item.empty() || !std::all_of(item.begin(), item.end(), [](char c) { return c >= '0' && c <= '9'; }))
        throw gpu::DeviceError("--devices takes all or device indices separated by commas (as `cdtgpu devices` "
                               "lists them), not '" + spec + "'");
      indices.push_back(gpu::pick_device(devices, item));  // range and features checked, with its message
    }
  }
  // The picked device first, under the name a job's own start uses ("" or --device), so that the start the
  // reader made for a job is the first worker's.
  std::stable_partition(indices.begin(), indices.end(), [&](size_t i) { return i == picked; });
  std::vector<DeviceWorker> workers;
  std::map<size_t, unsigned> copies;
  for (size_t i : indices)
    workers.push_back({i == picked ? device : std::to_string(i), copies[i]++,
                       "device " + std::to_string(i) + " (" + devices[i].name + ")"});
  return workers;
}

}  // namespace cdtgpu
