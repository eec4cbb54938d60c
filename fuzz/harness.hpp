// One entry per reader for the libFuzzer targets (fuzz_*.cpp) and for tests/fuzz_regression_test.cpp, which
// replays the crashes found. Bad input must end in InputError (exit code 2 in the CLI); any other exception,
// a crash or a sanitizer report is a bug.
//
//   fuzz_wkt(data, size);        // read_wkt on the bytes
//   fuzz_shapefile(data, size);  // [flags][shp length u32][shx length u32] shp shx dbf, from memory
//   fuzz_geotiff(data, size);    // read_geotiff_bytes on the bytes
//   fuzz_geojson(data, size);    // [flags] text;  fuzz_las(data, size): [flags] file, from memory
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "core/error.hpp"
#include "io/geotiff.hpp"
#include "io/mapped_files.hpp"
#include "io/read_geojson.hpp"
#include "io/read_las.hpp"
#include "io/readers.hpp"
#include "io/writers.hpp"

namespace cdtgpu::fuzz {

// Runs f; InputError is the expected outcome for bad bytes.
template <class F>
void expect_only_input_errors(F&& f) {
  try {
    f();
  } catch (const InputError&) {
  }
}

inline std::istringstream stream(const uint8_t* data, size_t size) {
  return std::istringstream(std::string(reinterpret_cast<const char*>(data), size));
}

inline void fuzz_wkt(const uint8_t* data, size_t size) {
  expect_only_input_errors([&] {
    InputSet in;
    auto s = stream(data, size);
    read_wkt(s, "fuzz.wkt", in);
  });
}

inline void fuzz_xyz(const uint8_t* data, size_t size) {
  expect_only_input_errors([&] {
    InputSet in;
    auto s = stream(data, size);
    read_xyz(s, "fuzz.xyz", in);
  });
}

// The parallel reader, which hands any fault in the data to the sequential one: both are exercised.
inline void fuzz_ascii_grid(const uint8_t* data, size_t size) {
  expect_only_input_errors([&] {
    InputSet in;
    read_ascii_grid_text(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.asc", in);
  });
}

// The GeoTIFF reader on the bytes, from memory. The limits keep a header that claims a huge raster from
// exhausting the fuzzer's memory and each execution short (64K cells: the seeds have 6; the CLI has no limit:
// such a file decodes, or fails, strip by strip).
inline void fuzz_geotiff(const uint8_t* data, size_t size) {
  expect_only_input_errors([&] {
    InputSet in;
    GeoTiffLimits limits;
    limits.max_cells = 1 << 16;
    limits.max_alloc = 64 << 20;
    read_geotiff_bytes(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.tif", in, limits);
  });
}

// A folder of this process's own for the file-based readers, removed at exit. In /dev/shm where there is one:
// rewriting a file on ext4 (auto_da_alloc) waits for the disk, which held the targets to ~180 runs a second.
inline const std::filesystem::path& scratch() {
  static const struct Dir {
    std::filesystem::path path;
    Dir()
        : path((std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                          : std::filesystem::temp_directory_path()) /
               ("cdtgpu-fuzz-" + std::to_string(::getpid()))) {
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } dir;
  return dir.path;
}

inline void put(const std::filesystem::path& p, const uint8_t* data, size_t size) {
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
}

// The first byte picks the format (obj, ply, wkt); the rest is the file.
inline void fuzz_mesh(const uint8_t* data, size_t size) {
  if (size < 1) return;
  static const char* const ext[] = {".obj", ".ply", ".wkt"};
  const std::filesystem::path p = scratch() / (std::string("mesh") + ext[data[0] % 3]);
  put(p, data + 1, size - 1);
  expect_only_input_errors([&] { read_mesh_file(p.string()); });
}

inline uint32_t le32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// [flags][shp length][shx length] shp shx dbf. Flags: bit 0 reads z from the DBF field ELEV, bit 1 leaves the
// .dbf out, bit 2 adds a geographic .prj.
inline void fuzz_shapefile(const uint8_t* data, size_t size) {
  if (size < 9) return;
  const uint8_t flags = data[0];
  size_t shp = le32(data + 1), shx = le32(data + 5);
  data += 9;
  size -= 9;
  shp = std::min(shp, size);
  shx = std::min(shx, size - shp);
  // Held in memory under a path of their own (io/mapped_files.hpp): the reader opens them as files, and no
  // byte goes through the file system.
  const std::string base = "/cdtgpu-fuzz-memory-" + std::to_string(::getpid()) + "/f";
  auto hold = [&](const char* ext, const uint8_t* bytes, size_t n) {
    files::put_memory_file(base + ext, std::string(reinterpret_cast<const char*>(bytes), n));
  };
  hold(".shp", data, shp);
  hold(".shx", data + shp, shx);
  files::remove_memory_file(base + ".dbf");
  files::remove_memory_file(base + ".prj");
  if (!(flags & 2)) hold(".dbf", data + shp + shx, size - shp - shx);
  if (flags & 4) {
    static const char prj[] = "GEOGCS[\"GCS_WGS_1984\"]";
    hold(".prj", reinterpret_cast<const uint8_t*>(prj), sizeof prj - 1);
  }
  expect_only_input_errors([&] {
    InputSet in;
    ReadOptions o;
    if (flags & 1) o.z_field = "ELEV";
    read_shapefile(base + ".shp", o, in);
  });
}

// [flags] text. Flags: bit 0 takes z from the feature property "z".
inline void fuzz_geojson(const uint8_t* data, size_t size) {
  if (size < 1) return;
  expect_only_input_errors([&] {
    InputSet in;
    in.nan_for_missing_z = data[0] & 2;
    read_geojson_text(std::string_view(reinterpret_cast<const char*>(data + 1), size - 1), "fuzz.geojson",
                      data[0] & 1 ? "z" : "", in);
  });
}

// [flags] file, held in memory. Flags: bit 0 keeps withheld points, bits 1-2 pick returns (all, first, last),
// bit 3 keeps class 2 only.
inline void fuzz_las(const uint8_t* data, size_t size) {
  if (size < 1) return;
  const std::string path = "/cdtgpu-fuzz-memory-" + std::to_string(::getpid()) + "/f.las";
  files::put_memory_file(path, std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  LasFilter filter;
  filter.keep_withheld = data[0] & 1;
  filter.returns = LasFilter::Returns((data[0] >> 1) % 3);
  if (data[0] & 8) {
    filter.classes.reset();
    filter.classes.set(2);
  }
  expect_only_input_errors([&] {
    InputSet in;
    read_las(path, filter, in);
  });
}

}  // namespace cdtgpu::fuzz
