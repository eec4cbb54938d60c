// The Vulkan pipeline cache kept on disk between runs, so that a run after the first creates its ~40 compute
// pipelines from the driver's compiled code instead of compiling SPIR-V again (issue 16: ~150 ms of a warm
// start on the H100, seconds on a fresh machine).
//
// One file per device, driver and build: $XDG_CACHE_HOME/cdtgpu (else ~/.cache/cdtgpu)/pipelines-<key>.bin,
// the key made of the device's pipelineCacheUUID, vendor and device ids, driver version and a hash of every
// embedded shader. The file carries its own header (those ids and a checksum of the payload); a missing,
// truncated, corrupt or foreign file is ignored and replaced, never fatal. CDTGPU_PIPELINE_CACHE=0 turns the
// cache off.
#pragma once
#include <vulkan/vulkan.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace cdtgpu::gpu {

// FNV-1a over every embedded shader's SPIR-V: another build of cdtgpu gets another cache file.
uint64_t shaders_hash();

// The cache file for this device and build; empty when the cache is off or there is no cache directory.
std::string pipeline_cache_path(const VkPhysicalDeviceProperties& props);

// The payload to seed vkCreatePipelineCache with, or nothing when the file is missing or does not match
// this device, driver and build, or its checksum fails.
std::vector<char> load_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props);

// Writes the payload through a temporary file and a rename. Returns false (and logs at debug level) on any
// failure: a cache that cannot be written only costs time.
bool save_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                         std::span<const char> payload);

}  // namespace cdtgpu::gpu
