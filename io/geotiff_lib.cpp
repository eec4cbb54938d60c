#include "io/geotiff_lib.hpp"

#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>

#ifndef CDTGPU_GEOTIFF_SONAME
#define CDTGPU_GEOTIFF_SONAME "libgeotiff.so"
#endif

namespace cdtgpu::tiff {

const GeoTiffLib& geotiff_lib() {
  static GeoTiffLib lib;
  static std::string failure;
  static std::once_flag once;
  std::call_once(once, [] {
    const std::string name = CDTGPU_GEOTIFF_SONAME;
    void* h = ::dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!h) {
      const char* why = ::dlerror();
      failure = "GeoTIFF needs libgeotiff (" + name + "): " + (why ? why : "cannot be loaded");
      return;
    }
    GeoTiffLib l;
    auto get = [&](auto& f, const char* symbol) {
      f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(::dlsym(h, symbol));
      if (!f && failure.empty()) failure = "GeoTIFF needs libgeotiff (" + name + "), which lacks " + symbol;
    };
    get(l.initialize, "XTIFFInitialize");
    get(l.new_ex, "GTIFNewEx");
    get(l.free, "GTIFFree");
    get(l.user_data, "GTIFGetUserData");
    get(l.key_get_short, "GTIFKeyGetSHORT");
    get(l.key_set, "GTIFKeySet");
    get(l.write_keys, "GTIFWriteKeys");
    if (failure.empty()) lib = l;  // the handle stays open for the process
  });
  if (!failure.empty()) throw std::runtime_error(failure);
  return lib;
}

}  // namespace cdtgpu::tiff
