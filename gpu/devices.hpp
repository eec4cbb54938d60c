// Several devices of one host for tiled runs (issue 29): which ones, and a context on each.
//
//   std::vector<gpu::DeviceInfo> all = gpu::list_devices();
//   std::vector<size_t> picked = gpu::select_devices(all, "all");     // or "0,2,3", or "" (one: pick_device's)
//   std::vector<std::unique_ptr<gpu::Context>> ctxs = gpu::create_contexts(picked, options);
//
// "all" is every usable hardware GPU (discrete, then integrated); CPU drivers (lavapipe) and virtual devices
// only when there is nothing else, one of them: they share the host's cores with the tiles' CPU work.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "gpu/context.hpp"

namespace cdtgpu::gpu {

// Indices into `devices`, ascending. `spec`: "all", a comma-separated list of indices, or "" for the one
// pick_device(devices, single) picks. Throws DeviceError naming what is wrong (an index out of range, a
// device that lacks a feature, a repeated index unless `repeats` (a batch's two workers on one GPU), none usable).
std::vector<size_t> select_devices(const std::vector<DeviceInfo>& devices, const std::string& spec,
                                   const std::string& single = "", bool repeats = false);

// A context on each device, created on threads of their own (each start is ~150 ms of driver work).
// `options.device` is ignored. A failure names the device.
std::vector<std::unique_ptr<Context>> create_contexts(const std::vector<size_t>& indices, ContextOptions options);

}  // namespace cdtgpu::gpu
