// Replays the inputs that crashed a fuzz target (fuzz/, scripts/fuzz.sh) through the same entry points: each
// must now end in InputError or be read, never crash or throw anything else. Files:
// tests/data/fuzz/<target>/.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz/harness.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kFuzzData = fs::path(CDTGPU_SOURCE_DIR) / "tests/data/fuzz";

std::vector<uint8_t> bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

// Runs every file of tests/data/fuzz/<target> through entry; returns how many there were.
template <class Entry>
size_t replay(const std::string& target, Entry entry) {
  size_t n = 0;
  if (!fs::is_directory(kFuzzData / target)) return 0;
  for (const auto& e : fs::directory_iterator(kFuzzData / target)) {
    const std::vector<uint8_t> b = bytes(e.path());
    SCOPED_TRACE(e.path().string());
    EXPECT_NO_THROW(entry(b.data(), b.size()));
    ++n;
  }
  return n;
}

TEST(FuzzRegression, Wkt) { replay("wkt", cdtgpu::fuzz::fuzz_wkt); }
TEST(FuzzRegression, Xyz) { replay("xyz", cdtgpu::fuzz::fuzz_xyz); }
TEST(FuzzRegression, AsciiGrid) { replay("ascii_grid", cdtgpu::fuzz::fuzz_ascii_grid); }
TEST(FuzzRegression, Mesh) { replay("mesh", cdtgpu::fuzz::fuzz_mesh); }
TEST(FuzzRegression, Shapefile) { replay("shapefile", cdtgpu::fuzz::fuzz_shapefile); }
TEST(FuzzRegression, GeoTiff) { replay("geotiff", cdtgpu::fuzz::fuzz_geotiff); }
TEST(FuzzRegression, GeoJson) { replay("geojson", cdtgpu::fuzz::fuzz_geojson); }
TEST(FuzzRegression, Las) { replay("las", cdtgpu::fuzz::fuzz_las); }

}  // namespace
