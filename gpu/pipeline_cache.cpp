// The on-disk pipeline cache: see pipeline_cache.hpp.
#include "gpu/pipeline_cache.hpp"

#include <unistd.h>

#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include "gpu/passes.hpp"

namespace cdtgpu::gpu {
namespace {

constexpr char kMagic[8] = {'C', 'D', 'T', 'G', 'P', 'U', 'P', 'C'};
constexpr uint32_t kVersion = 1;

// Our header before the driver's data. The driver checks its own header too, but what follows it is opaque
// to us and a driver given damaged data may crash: the checksum keeps damaged files from reaching it.
struct Header {
  char magic[8];
  uint32_t version;
  uint32_t vendor_id, device_id, driver_version;
  uint8_t cache_uuid[VK_UUID_SIZE];
  uint64_t shaders;
  uint64_t payload_size;
  uint64_t payload_hash;
};

uint64_t fnv1a(const void* data, size_t n, uint64_t h = 1469598103934665603ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

Header header_for(const VkPhysicalDeviceProperties& props, std::span<const char> payload) {
  Header h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.version = kVersion;
  h.vendor_id = props.vendorID;
  h.device_id = props.deviceID;
  h.driver_version = props.driverVersion;
  std::memcpy(h.cache_uuid, props.pipelineCacheUUID, VK_UUID_SIZE);
  h.shaders = shaders_hash();
  h.payload_size = payload.size();
  h.payload_hash = fnv1a(payload.data(), payload.size());
  return h;
}

std::string hex(const uint8_t* p, size_t n) {
  std::string s;
  char b[3];
  for (size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02x", p[i]);
    s += b;
  }
  return s;
}

}  // namespace

uint64_t shaders_hash() {
  static const uint64_t hash = [] {
    uint64_t h = 1469598103934665603ull;
    for (const std::string& name : shader_names()) {
      h = fnv1a(name.data(), name.size(), h);
      const std::span<const uint32_t> code = shader_spirv(name);
      h = fnv1a(code.data(), code.size_bytes(), h);
    }
    return h;
  }();
  return hash;
}

std::string pipeline_cache_path(const VkPhysicalDeviceProperties& props) {
  const char* off = std::getenv("CDTGPU_PIPELINE_CACHE");
  if (off && std::strcmp(off, "0") == 0) return {};
  std::filesystem::path dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    dir = xdg;
  else if (const char* home = std::getenv("HOME"); home && *home)
    dir = std::filesystem::path(home) / ".cache";
  else
    return {};
  char key[64];
  std::snprintf(key, sizeof key, "-%04x-%04x-%08x-%016llx", props.vendorID, props.deviceID, props.driverVersion,
                static_cast<unsigned long long>(shaders_hash()));
  return (dir / "cdtgpu" / ("pipelines-" + hex(props.pipelineCacheUUID, VK_UUID_SIZE) + key + ".bin")).string();
}

std::vector<char> load_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props) {
  if (path.empty()) return {};
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Header h{};
  if (bytes.size() < sizeof h) {
    spdlog::debug("pipeline cache {}: too short, ignored", path);
    return {};
  }
  std::memcpy(&h, bytes.data(), sizeof h);
  std::vector<char> payload(bytes.begin() + sizeof h, bytes.end());
  const Header want = header_for(props, payload);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0 || h.version != kVersion || h.vendor_id != want.vendor_id ||
      h.device_id != want.device_id || h.driver_version != want.driver_version ||
      std::memcmp(h.cache_uuid, want.cache_uuid, VK_UUID_SIZE) != 0 || h.shaders != want.shaders) {
    spdlog::debug("pipeline cache {}: another device, driver or build, ignored", path);
    return {};
  }
  if (h.payload_size != want.payload_size || h.payload_hash != want.payload_hash) {
    spdlog::debug("pipeline cache {}: damaged, ignored", path);
    return {};
  }
  return payload;
}

bool save_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                         std::span<const char> payload) {
  if (path.empty()) return false;
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  // Per process and thread: a tiled run's devices, closed at once on threads of their own, may share a path.
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid()) + "-" +
                          std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id()));
  const Header h = header_for(props, payload);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    out.write(payload.data(), std::streamsize(payload.size()));
    out.close();
    if (!out) {
      std::filesystem::remove(tmp, ec);
      spdlog::debug("pipeline cache {}: cannot write", path);
      return false;
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    spdlog::debug("pipeline cache {}: cannot rename into place", path);
    return false;
  }
  return true;
}

}  // namespace cdtgpu::gpu
