#include "cli/batch_devices.hpp"

#include <algorithm>
#include <map>

#include "gpu/context.hpp"
#include "gpu/devices.hpp"

namespace cdtgpu {

std::vector<DeviceWorker> batch_device_workers(const std::string& spec, const std::string& device) {
  const std::vector<gpu::DeviceInfo> devices = gpu::list_devices();
  const size_t picked = gpu::pick_device(devices, device);
  std::vector<size_t> indices = device.empty() ? gpu::select_devices(devices, spec, "", /*repeats=*/true)
                                               : std::vector<size_t>{picked};
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
