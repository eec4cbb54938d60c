// The device workers of `cdtgpu batch` (issue 29): one thread a worker runs the jobs' device stages (triangulate,
// regions, grid, contours), each on a GPU of its own, taking the next job read as it becomes free.
//
//   std::vector<DeviceWorker> w = batch_device_workers("all", "");  // one a hardware GPU; "0,0": two on GPU 0
//
// Not the default: on the 2 x H200 host two workers ran 24 jobs of 2M points + 500K contour vertices in 2.5-3.0 s
// against 3.3 for one, and 8 jobs of 10M no faster (the host's read, prepare, resolve and write, each on all
// cores, bound a batch there; docs/performance.md).
//
// A worker's device is what a job's --device names: "" for the one a single run picks, else an index. `copy`
// tells two workers of one GPU apart (each has a Vulkan device of its own there).
#pragma once
#include <string>
#include <vector>

namespace cdtgpu {

struct DeviceWorker {
  std::string device;
  unsigned copy = 0;
  std::string name;  // for the log: "device 1 (NVIDIA H200)"
};

// `spec`: "all" (every hardware GPU, or the one device a single run picks where there is no other), or indices
// as `cdtgpu devices` lists them, an index given twice running two workers on that GPU. `device` (the batch's
// --device): one worker there. Lists the devices (a Vulkan instance of its own); throws gpu::DeviceError
// naming a bad index or a device that cannot run cdtgpu.
std::vector<DeviceWorker> batch_device_workers(const std::string& spec, const std::string& device);

}  // namespace cdtgpu
