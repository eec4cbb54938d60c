// End to end: the cdtgpu binary on real files, one test per output format and per bad-input case.
#include <cmath>
#include <gtest/gtest.h>

#include <algorithm>
#include "gpu/context.hpp"
#include "tests/binary_test.hpp"
#include "io/tiles_dir.hpp"
#include "io/writers.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <iomanip>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

using cdtgpu::test::Result;

// The name of the first Vulkan device the GPU backend can use (lavapipe in CI); empty if none.
std::string first_usable_device() {
  for (const cdtgpu::gpu::DeviceInfo& d : cdtgpu::gpu::list_devices())
    if (d.missing.empty()) return d.name;
  return "";
}

class Cli : public cdtgpu::test::BinaryTest {
 public:
  Cli() : BinaryTest("cdtgpu_cli_") {}

  // Files in dir other than the inputs we wrote: a failed run must leave none (no half file, no tmp file).
  size_t files_matching(const std::string& stem) const {
    size_t n = 0;
    for (auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().rfind(stem, 0) == 0) ++n;
    return n;
  }

  // A small terrain: 400 jittered DEM points, two contour lines, one building ring, in projected metres.
  void write_terrain() const {
    write("dem.csv", cdtgpu::test::jittered_dem_csv(7));
    write("lines.wkt",
          "LINESTRING Z (500005 6000005 110, 500100 6000050 111, 500185 6000180 112)\n"
          "LINESTRING (500020 6000150, 500060 6000120)\n"
          "POLYGON Z ((500120 6000020 130, 500140 6000020 130, 500140 6000040 130, 500120 6000040 130, "
          "500120 6000020 130))\n");
  }
};

TEST_F(Cli, EachFormatIsWrittenAndPassesVerify) {
  write_terrain();
  for (std::string ext : {"obj", "ply", "wkt"}) {
    std::string out = path("tin." + ext);
    Result r = run("triangulate " + path("dem.csv") + " " + path("lines.wkt") + " -o " + out + " -q");
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_TRUE(fs::exists(out));
    Result v = run("verify " + out + " " + path("dem.csv") + " " + path("lines.wkt"));
    EXPECT_EQ(v.code, 0) << ext << ": " << v.err;
  }
  Result r = run("triangulate " + path("dem.csv") + " -o " + path("ascii.ply") + " --ascii -q");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("ascii.ply")).rfind("ply\nformat ascii 1.0\n", 0), 0u);
  r = run("triangulate " + path("dem.csv") + " -o " + path("mp.wkt") + " --wkt-multipolygon -q");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("mp.wkt")).rfind("MULTIPOLYGON Z", 0), 0u);
}

TEST_F(Cli, SameInputGivesSameBytes) {
  write_terrain();
  std::string args = "triangulate " + path("dem.csv") + " " + path("lines.wkt") + " -q -o ";
  ASSERT_EQ(run(args + path("a.ply")).code, 0);
  ASSERT_EQ(run(args + path("b.ply")).code, 0);
  EXPECT_EQ(slurp(path("a.ply")), slurp(path("b.ply")));
  // Input order of the files does not matter for the vertex and triangle order.
  ASSERT_EQ(run("triangulate " + path("lines.wkt") + " " + path("dem.csv") + " -q -o " + path("c.obj")).code, 0);
  ASSERT_EQ(run(args + path("d.obj")).code, 0);
  EXPECT_EQ(slurp(path("c.obj")), slurp(path("d.obj")));
}

// The GPU backend, forced (lavapipe included); its bytes equal the CGAL reference backend's in every format.
TEST_F(Cli, GpuBackendWritesTheSameBytesAsCgal) {
  write_terrain();
  std::string in = path("dem.csv") + " " + path("lines.wkt");
  for (std::string ext : {"obj", "ply", "wkt"}) {
    Result g = run("triangulate " + in + " -q --backend gpu -o " + path("gpu." + ext) + " --stats " +
                   path("gpu.json"));
    ASSERT_EQ(g.code, 0) << g.err;
    Result c = run("triangulate " + in + " -q --backend cgal -o " + path("cgal." + ext));
    ASSERT_EQ(c.code, 0) << c.err;
    EXPECT_EQ(slurp(path("gpu." + ext)), slurp(path("cgal." + ext))) << ext;
  }
  auto stats = nlohmann::json::parse(slurp(path("gpu.json")));
  EXPECT_EQ(stats["backend"], "gpu");
  EXPECT_FALSE(stats["device"].get<std::string>().empty());
  EXPECT_GT(stats["gpu_stage_ms"]["total"].get<double>(), 0);
  EXPECT_TRUE(stats["gpu_stage_ms"].contains("dt flip"));
  EXPECT_TRUE(stats["gpu_stage_ms"].contains("cdt crossing detection"));
  Result bad = run("triangulate " + in + " -q --backend fast -o " + path("x.ply"));
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(files_matching("x."), 0u);
  Result nodev = run("triangulate " + in + " -q --backend gpu --device no-such-gpu -o " + path("y.ply"));
  EXPECT_EQ(nodev.code, 3) << nodev.err;
  EXPECT_NE(nodev.err.find("no-such-gpu"), std::string::npos) << nodev.err;
  EXPECT_NE(nodev.err.find("--backend cgal"), std::string::npos) << nodev.err;  // the way out is named
  EXPECT_EQ(files_matching("y."), 0u);
}

// A run closes its device on a thread of its own once the device's work is done, beside the writing, and a
// batch after its last job: the process must still wait for it, and the context saves the pipeline cache as it
// goes. In a fresh cache folder (the driver's own shader cache left where it was, or lavapipe would compile
// everything again) both leave the cache file behind.
TEST_F(Cli, GpuRunsSaveThePipelineCacheBeforeTheyExit) {
  write_terrain();
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const char* home = std::getenv("HOME");
  if (!xdg && !home) GTEST_SKIP() << "neither XDG_CACHE_HOME nor HOME is set: no pipeline cache";
  const std::string old_cache = xdg ? xdg : std::string(home) + "/.cache";
  if (!std::getenv("MESA_SHADER_CACHE_DIR")) setenv("MESA_SHADER_CACHE_DIR", (old_cache + "/mesa_shader_cache").c_str(), 1);
  if (!std::getenv("__GL_SHADER_DISK_CACHE_PATH")) setenv("__GL_SHADER_DISK_CACHE_PATH", (old_cache + "/nvidia").c_str(), 1);
  const std::string in = path("dem.csv") + " " + path("lines.wkt");
  write("jobs.txt", in + " --backend gpu -o " + path("b.ply") + "\n");
  auto cache_files = [&](const std::string& dir) {
    size_t n = 0;
    for (const auto& e : fs::recursive_directory_iterator(dir))
      n += e.is_regular_file() && e.path().filename().string().rfind("pipelines", 0) == 0 && e.file_size() > 0;
    return n;
  };
  for (const std::string& how : {"triangulate " + in + " -q --backend gpu -o " + path("a.ply"), "batch " + path("jobs.txt") + " -q"}) {
    const std::string dir = path(how.substr(0, 5) + "-cache");
    fs::create_directories(dir);
    setenv("XDG_CACHE_HOME", dir.c_str(), 1);
    const Result r = run(how);
    if (xdg) setenv("XDG_CACHE_HOME", xdg, 1); else unsetenv("XDG_CACHE_HOME");
    ASSERT_EQ(r.code, 0) << how << ": " << r.err;
    EXPECT_EQ(cache_files(dir), 1u) << how;
  }
}

// --initial-dt voronoi (issue 30): the GPU Delaunay build from the digital Voronoi diagram writes the default's
// bytes; it implies the GPU backend and is refused with CGAL's.
TEST_F(Cli, VoronoiInitialDtWritesTheSameBytes) {
  if (first_usable_device().empty()) GTEST_SKIP() << "no Vulkan device";
  write_terrain();
  std::string in = path("dem.csv") + " " + path("lines.wkt");
  Result d = run("triangulate " + in + " -q --backend gpu -o " + path("default.ply"));
  ASSERT_EQ(d.code, 0) << d.err;
  Result v = run("triangulate " + in + " -q --initial-dt voronoi -o " + path("voronoi.ply") + " --stats " +
                 path("vd.json"));
  ASSERT_EQ(v.code, 0) << v.err;
  EXPECT_EQ(slurp(path("default.ply")), slurp(path("voronoi.ply")));
  auto stats = nlohmann::json::parse(slurp(path("vd.json")));
  EXPECT_EQ(stats["backend"], "gpu");
  EXPECT_TRUE(stats["gpu_stage_ms"].contains("dt vd flood")) << stats["gpu_stage_ms"].dump();
  Result c = run("triangulate " + in + " -q --backend cgal --initial-dt voronoi -o " + path("c.ply"));
  EXPECT_EQ(c.code, 2);
  EXPECT_NE(c.err.find("--initial-dt voronoi"), std::string::npos) << c.err;
  EXPECT_EQ(files_matching("c."), 0u);
  Result bad = run("triangulate " + in + " -q --initial-dt jfa -o " + path("j.ply"));
  EXPECT_EQ(bad.code, 2);
}

// --backend auto (the default): CGAL for small inputs, without touching Vulkan; for large ones the GPU only where
// it is hardware (on lavapipe, CGAL). Whatever it picks, the bytes are the same, and the stats say why.
TEST_F(Cli, AutoBackendPicksByInputSizeAndDevice) {
  write_terrain();
  std::string in = path("dem.csv") + " " + path("lines.wkt");
  ASSERT_EQ(run("triangulate " + in + " -q --backend cgal -o " + path("cgal.ply")).code, 0);
  Result small = run("triangulate " + in + " -q -o " + path("small.ply") + " --stats " + path("small.json"));
  ASSERT_EQ(small.code, 0) << small.err;
  auto stats = nlohmann::json::parse(slurp(path("small.json")));
  EXPECT_EQ(stats["backend"], "cgal");
  // 100K points, or 45K a core beyond that (cli/gpu_start.hpp)
  const unsigned cores = std::clamp(std::thread::hardware_concurrency(), 1u, 32u);
  const std::string fewer = "fewer than " + std::to_string(std::max<uint64_t>(100000, 45000ull * cores));
  EXPECT_NE(stats["backend_reason"].get<std::string>().find(fewer), std::string::npos) << stats["backend_reason"];
  EXPECT_FALSE(stats.contains("device"));
  EXPECT_EQ(slurp(path("small.ply")), slurp(path("cgal.ply")));

  // Every input counts as large: the device decides.
  bool hardware = false;
  for (const cdtgpu::gpu::DeviceInfo& d : cdtgpu::gpu::list_devices()) hardware = hardware || (d.type != "cpu" && d.missing.empty());
  ::setenv("CDTGPU_AUTO_MIN_POINTS", "1", 1);
  Result big = run("triangulate " + in + " -q -o " + path("large.ply") + " --stats " + path("large.json"));
  Result nodev = run("triangulate " + in + " -q --device no-such-gpu -o " + path("nodev.ply"));
  ::unsetenv("CDTGPU_AUTO_MIN_POINTS");
  ASSERT_EQ(big.code, 0) << big.err;
  stats = nlohmann::json::parse(slurp(path("large.json")));
  EXPECT_EQ(stats["backend"], hardware ? "gpu" : "cgal") << stats["backend_reason"];
  if (!hardware) {
    EXPECT_NE(stats["backend_reason"].get<std::string>().find("CPU Vulkan driver"), std::string::npos)
        << stats["backend_reason"];
  }
  EXPECT_EQ(slurp(path("large.ply")), slurp(path("cgal.ply")));
  // No usable device: auto still triangulates, on the CPU.
  EXPECT_EQ(nodev.code, 0) << nodev.err;
  EXPECT_EQ(slurp(path("nodev.ply")), slurp(path("cgal.ply")));
}

// CDTGPU_HOST_MEMORY stands for the machine's memory: a run whose points cannot fit is refused before it reads
// (exit 3, the need and the memory named, the old output kept); one that fits runs, and --stats gives its peak.
TEST_F(Cli, RunTooLargeForHostMemoryIsRefusedBeforeReading) {
  std::ostringstream xyz;
  for (int i = 0; i < 250; ++i)
    for (int j = 0; j < 200; ++j) xyz << 500000 + i * 2 << ' ' << 6000000 + j * 2 + (i % 3) * 0.25 << ' ' << i % 7 << '\n';
  write("dem.xyz", xyz.str());  // 50000 points, too few for auto's GPU or for tiles: one CGAL run, ~16 MB
  write("tin.ply", "old bytes");
  ::setenv("CDTGPU_HOST_MEMORY", "5000000", 1);
  Result small = run("triangulate " + path("dem.xyz") + " -o " + path("tin.ply"));
  ::setenv("CDTGPU_HOST_MEMORY", "100000000", 1);
  Result roomy = run("triangulate " + path("dem.xyz") + " -q -o " + path("roomy.ply") + " --stats " + path("s.json"));
  ::unsetenv("CDTGPU_HOST_MEMORY");
  EXPECT_EQ(small.code, 3) << small.err;
  EXPECT_NE(small.err.find("input points (estimated from the input files) need about 16."), std::string::npos)
      << small.err;  // the estimate from the file's size is within a few per cent of the 50000 points
  EXPECT_NE(small.err.find("(315 bytes a point)"), std::string::npos) << small.err;  // all in CGAL at once
  EXPECT_NE(small.err.find("this machine has 5.0 MB"), std::string::npos) << small.err;
  EXPECT_EQ(small.err.find("read:"), std::string::npos) << "refused before reading: " << small.err;
  EXPECT_EQ(slurp(path("tin.ply")), "old bytes");
  ASSERT_EQ(roomy.code, 0) << roomy.err;
  const auto stats = nlohmann::json::parse(slurp(path("s.json")));
  EXPECT_GT(stats["peak_host_bytes"].get<uint64_t>(), 1000000u);
}

// Auto that finds no GPU after all, on an input the CPU tiles by itself (100K points or more): the tiles take
// what the resolve begun for the device made. A second resolve beside it freed the prepared input under the
// first (a crash one run in three at 250K points). So the stats hold the other threads' resolve and no second;
// the bytes are CGAL's. (Where auto finds a hardware GPU, only the bytes are checked.)
TEST_F(Cli, AutoWithoutAGpuTilesWhatItsResolveMade) {
  std::ostringstream xyz;
  xyz << std::fixed << std::setprecision(2);
  for (int i = 0; i < 400; ++i)
    for (int j = 0; j < 300; ++j) xyz << 500000 + i * 2 << ' ' << 6000000 + j * 2 + (i % 3) * 0.25 << ' ' << i % 7 << '\n';
  write("dem.xyz", xyz.str());  // 120000 points: CPU tiles by default
  ASSERT_EQ(run("triangulate " + path("dem.xyz") + " -q --backend cgal -o " + path("cgal.ply")).code, 0);
  ::setenv("CDTGPU_AUTO_MIN_POINTS", "1", 1);
  const Result r = run("triangulate " + path("dem.xyz") + " -q -o " + path("auto.ply") + " --stats " + path("s.json"));
  ::unsetenv("CDTGPU_AUTO_MIN_POINTS");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("auto.ply")), slurp(path("cgal.ply")));
  const auto stats = nlohmann::json::parse(slurp(path("s.json")));
  if (stats["backend"] == "cgal") {
    EXPECT_TRUE(stats["stage_ms"].contains("triangulate: resolve (other threads)")) << stats["stage_ms"];
    EXPECT_FALSE(stats["stage_ms"].contains("triangulate: resolve")) << "resolved twice: " << stats["stage_ms"];
    EXPECT_GE(stats["counts"].value("tiles", 0), 2) << stats.dump();
  }
}

// CDTGPU_DEVICE_MEMORY_LIMIT caps what the GPU backend may hold on the device: a forced GPU run that needs more
// fails (exit 3, the limit named, nothing written); auto leaves it to CGAL with the same bytes and says why. A
// device named with --device is used by auto even when it is a CPU driver, which lets lavapipe test this.
TEST_F(Cli, DeviceMemoryCapFailsAForcedGpuAndAutoFallsBack) {
  write_terrain();
  const std::string in = path("dem.csv") + " " + path("lines.wkt");
  const std::string device = first_usable_device();
  ASSERT_FALSE(device.empty());
  ASSERT_EQ(run("triangulate " + in + " -q --backend cgal -o " + path("cgal.ply")).code, 0);
  ::setenv("CDTGPU_AUTO_MIN_POINTS", "1", 1);
  ::setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "64K", 1);
  // The failure comes after the file's vertices were begun (io/mesh_file_ahead): the old file stays, no
  // temporary file is left.
  write("forced.ply", "the old output\n");
  Result forced = run("triangulate " + in + " -q --backend gpu -o " + path("forced.ply"));
  Result fell = run("triangulate " + in + " -q --device '" + device + "' -o " + path("auto.ply") + " --stats " +
                    path("auto.json"));
  ::setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "8G", 1);
  Result roomy = run("triangulate " + in + " -q --device '" + device + "' -o " + path("roomy.ply") + " --stats " +
                     path("roomy.json"));
  ::setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "lots", 1);
  Result bad = run("triangulate " + in + " -q --backend gpu -o " + path("bad.ply"));
  ::unsetenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  ::unsetenv("CDTGPU_AUTO_MIN_POINTS");

  EXPECT_EQ(forced.code, 3) << forced.err;
  EXPECT_NE(forced.err.find("over CDTGPU_DEVICE_MEMORY_LIMIT = 65536 bytes"), std::string::npos) << forced.err;
  EXPECT_NE(forced.err.find("--backend cgal"), std::string::npos) << forced.err;
  EXPECT_EQ(slurp(path("forced.ply")), "the old output\n");
  EXPECT_EQ(files_matching("forced.ply"), 1u) << "a temporary file was left";
  ASSERT_EQ(fell.code, 0) << fell.err;
  auto stats = nlohmann::json::parse(slurp(path("auto.json")));
  EXPECT_EQ(stats["backend"], "cgal");
  EXPECT_NE(stats["backend_reason"].get<std::string>().find("out of device memory"), std::string::npos)
      << stats["backend_reason"];
  EXPECT_EQ(slurp(path("auto.ply")), slurp(path("cgal.ply")));
  ASSERT_EQ(roomy.code, 0) << roomy.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(path("roomy.json")))["backend"], "gpu");
  EXPECT_EQ(slurp(path("roomy.ply")), slurp(path("cgal.ply")));
  EXPECT_EQ(bad.code, 3) << bad.err;
  EXPECT_NE(bad.err.find("CDTGPU_DEVICE_MEMORY_LIMIT=lots: not a byte count"), std::string::npos) << bad.err;
}

TEST_F(Cli, StdinToStdoutAndStats) {
  write("pts.wkt", "MULTIPOINT ((0 0), (1 0), (0 1), (1 1), (0.5 0.5))\nPOINT (1 1)\n");
  Result r = run("triangulate - --crs none --format wkt -o - --stats " + path("s.json") + " < " + path("pts.wkt"),
                 path("out.wkt"));
  ASSERT_EQ(r.code, 0) << r.err;
  std::string wkt = slurp(path("out.wkt"));
  EXPECT_EQ(wkt.rfind("TIN Z (((", 0), 0u) << wkt;
  auto stats = nlohmann::json::parse(slurp(path("s.json")));
  EXPECT_EQ(stats["counts"]["input_points"], 6);
  EXPECT_EQ(stats["counts"]["merged_duplicates"], 1);
  EXPECT_EQ(stats["counts"]["vertices"], 5);
  EXPECT_EQ(stats["counts"]["triangles"], 4);
  EXPECT_EQ(stats["crs"], "none");
  for (const char* stage : {"read", "project", "prepare", "triangulate", "write"})
    EXPECT_TRUE(stats["stage_ms"].contains(stage)) << stage;
}

TEST_F(Cli, LonLatIsProjectedToTheUtmZoneOfItsCentre) {
  // Around Katoomba NSW: 150.31E 33.71S lies in UTM zone 56S.
  write("ll.xyz", "150.30 -33.70 1000\n150.32 -33.70 1010\n150.31 -33.72 1005\n150.31 -33.69 990\n");
  Result r = run("triangulate " + path("ll.xyz") + " -o " + path("t.obj") + " --stats " + path("s.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  auto stats = nlohmann::json::parse(slurp(path("s.json")));
  EXPECT_NE(stats["crs"].get<std::string>().find("56S"), std::string::npos) << stats["crs"];
  EXPECT_NE(slurp(path("t.obj")).find("56S"), std::string::npos);
}

TEST_F(Cli, VerifyRejectsAMeshOfOtherInputs) {
  write_terrain();
  ASSERT_EQ(run("triangulate " + path("dem.csv") + " -q -o " + path("dem.obj")).code, 0);
  // The DEM-only mesh does not honour the contour and building constraints.
  Result v = run("verify " + path("dem.obj") + " " + path("dem.csv") + " " + path("lines.wkt"));
  EXPECT_EQ(v.code, 1) << v.err;
  EXPECT_NE(v.err.find("NOT"), std::string::npos) << v.err;
}

// Per-input options: a boundary and a hole cut the TIN, a 2D footprint is draped, and both backends agree.
TEST_F(Cli, RolesAndDrapeWithBothBackends) {
  write_terrain();
  write("area.wkt", "POLYGON ((500030 6000030, 500170 6000030, 500170 6000170, 500030 6000170, 500030 6000030))\n");
  write("lake.wkt", "POLYGON ((500060 6000060, 500090 6000060, 500090 6000090, 500060 6000090, 500060 6000060))\n");
  write("house.wkt", "POLYGON ((500150.5 6000100.5, 500160.5 6000100.5, 500160.5 6000110.5, 500150.5 6000110.5))\n");
  const std::string in = path("dem.csv") + " " + path("area.wkt") + ":role=boundary " + path("lake.wkt") +
                         ":role=hole " + path("house.wkt") + ":z=drape --max-edge 50 -q";
  Result c = run("triangulate " + in + " --backend cgal -o " + path("cgal.ply") + " --stats " + path("c.json"));
  ASSERT_EQ(c.code, 0) << c.err;
  Result g = run("triangulate " + in + " -o " + path("gpu.ply"));
  ASSERT_EQ(g.code, 0) << g.err;
  EXPECT_EQ(slurp(path("gpu.ply")), slurp(path("cgal.ply")));
  auto stats = nlohmann::json::parse(slurp(path("c.json")));
  EXPECT_EQ(stats["counts"]["draped_vertices"], 4);
  EXPECT_GT(stats["counts"]["triangles_outside_regions"].get<int>(), 100);
  EXPECT_GT(stats["counts"]["vertices_outside_regions"].get<int>(), 100);
  // The draped house's corners sit on the terrain (z about 100 + i + j / 2 there), not at 0.
  Result w = run("triangulate " + in + " --backend cgal --format wkt -o -", path("tin.wkt"));
  ASSERT_EQ(w.code, 0) << w.err;
  const std::string wkt = slurp(path("tin.wkt"));
  const size_t at = wkt.find("500150.5 6000100.5 ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::stod(wkt.substr(at + 19)), 100.0);

  // verify understands the roles: without --max-edge the mesh is the CDT restricted to the domain.
  const std::string roles = path("dem.csv") + " " + path("area.wkt") + ":role=boundary " + path("lake.wkt") +
                            ":role=hole " + path("house.wkt") + ":z=drape -q";
  ASSERT_EQ(run("triangulate " + roles + " --backend cgal -o " + path("roles.ply")).code, 0);
  Result v = run("verify " + path("roles.ply") + " " + roles);
  EXPECT_EQ(v.code, 0) << v.err;
  // The lake given as a breakline: the mesh has a hole where verify expects triangles.
  v = run("verify " + path("roles.ply") + " " + path("dem.csv") + " " + path("area.wkt") + ":role=boundary " +
          path("lake.wkt") + " " + path("house.wkt") + ":z=drape");
  EXPECT_EQ(v.code, 1) << v.err;
  EXPECT_NE(v.err.find("missing"), std::string::npos) << v.err;
}

// verify --max-edge: a C-shaped point set whose bay --max-edge trims; verify checks the trimming both ways.
TEST_F(Cli, VerifyChecksMaxEdgeTrimming) {
  std::string xyz;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j)
      if (i < 16 || std::abs(j - 20) > 8) xyz += std::to_string(500000 + 5 * i) + " " + std::to_string(6000000 + 5 * j) + " " + std::to_string(i + j) + "\n";
  write("coast.xyz", xyz);
  const std::string coast = path("coast.xyz");
  ASSERT_EQ(run("triangulate " + coast + " --max-edge 20 -o " + path("trimmed.ply") + " -q").code, 0);
  ASSERT_EQ(run("triangulate " + coast + " -o " + path("whole.ply") + " -q").code, 0);
  Result v = run("verify " + path("trimmed.ply") + " " + coast + " --max-edge 20");
  EXPECT_EQ(v.code, 0) << v.err;
  v = run("verify " + path("trimmed.ply") + " " + coast);
  EXPECT_EQ(v.code, 1) << v.err;
  v = run("verify " + path("whole.ply") + " " + coast + " --max-edge 20");
  EXPECT_EQ(v.code, 1) << v.err;
  EXPECT_NE(v.err.find("not a triangle of the CDT inside the domain"), std::string::npos) << v.err;
  EXPECT_EQ(run("verify " + path("whole.ply") + " " + coast + " --max-edge -1").code, 2);
}

// Boundary lines that do not close: triangulate warns, naming an open end (their region leaks, docs/rules.md);
// verify says it does not check them (exit 2). The same boundary closed: no warning, verified.
TEST_F(Cli, OpenBoundaryLinesAreNamed) {
  std::string xyz;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) xyz += std::to_string(5 * i) + " " + std::to_string(5 * j) + " " + std::to_string(i + j) + "\n";
  write("grid.xyz", xyz);
  write("open.wkt", "LINESTRING (20 20, 80 20, 80 80, 20 80)\n");
  write("ring.wkt", "POLYGON ((20 20, 80 20, 80 80, 20 80, 20 20))\n");
  for (const std::string b : {"open", "ring"}) {
    const std::string in = path("grid.xyz") + " " + path(b + ".wkt") + ":role=boundary,z=0 --crs none";
    Result t = run("triangulate " + in + " --backend cgal -o " + path(b + ".ply"));
    ASSERT_EQ(t.code, 0) << t.err;
    Result v = run("verify " + path(b + ".ply") + " " + in);
    if (b == "ring") {
      EXPECT_EQ(t.err.find("do not close"), std::string::npos) << t.err;
      EXPECT_EQ(v.code, 0) << v.err;
      continue;
    }
    EXPECT_NE(t.err.find("boundary and hole lines do not close (2 open ends, the first at (20, 20))"),
              std::string::npos) << t.err;
    EXPECT_EQ(v.code, 2) << v.err;
    EXPECT_NE(v.err.find("do not close (2 open ends, the first at (20, 20))"), std::string::npos) << v.err;
  }
}

// --devices: tiles spread over the devices it names give the same bytes; a list that is not one is a usage error.
TEST_F(Cli, TilesOnTheDevicesListed) {
  write_terrain();
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " -q";
  ASSERT_EQ(run("triangulate " + in + " --backend cgal -o " + path("one.ply")).code, 0);
  Result r = run("triangulate " + in + " --backend gpu --max-tile-points 100 --devices all -o " + path("all.ply") +
                 " --stats " + path("all.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("all.ply")), slurp(path("one.ply")));
  auto stats = nlohmann::json::parse(slurp(path("all.json")));
  EXPECT_GE(stats["counts"]["tile_devices"].get<int>(), 1);
  EXPECT_GT(stats["counts"]["tiles"].get<int>(), 2);
  r = run("triangulate " + in + " --devices 0,,1 -o " + path("x.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("device indices separated by commas"), std::string::npos) << r.err;
  r = run("triangulate " + in + " --backend gpu --max-tile-points 100 --devices 99 -o " + path("x.ply"));
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("out of range"), std::string::npos) << r.err;
}

TEST_F(Cli, UnknownInputOptionIsAUsageError) {
  write_terrain();
  Result r = run("triangulate " + path("dem.csv") + ":colour=red -o " + path("out.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("colour"), std::string::npos) << r.err;
  r = run("triangulate " + path("dem.csv") + ":z=ELEV -o " + path("out.ply"));
  EXPECT_EQ(r.code, 2) << r.err;  // a field name on a text file
  EXPECT_EQ(files_matching("out"), 0u);
}

// Bad input: exit code 2, a message naming the file (and line where there is one), no output written.
void expect_bad(const Cli& t, const Result& r, const std::string& file, const std::string& detail) {
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(detail), std::string::npos) << r.err;
  EXPECT_EQ(t.files_matching("out"), 0u) << "a failed run left an output file";
}

TEST_F(Cli, MalformedWktNamesTheLine) {
  write("bad.wkt", "POINT (0 0)\nPOINT (1 0)\nLINESTRING (0 0, 1\nPOINT (0 1)\n");
  expect_bad(*this, run("triangulate " + path("bad.wkt") + " -o " + path("out.ply")), "bad.wkt", "line 3");
}

TEST_F(Cli, NonFiniteCoordinateIsRejected) {
  write("nan.xyz", "0 0 1\n1 0 nan\n0 1 2\n");
  expect_bad(*this, run("triangulate " + path("nan.xyz") + " -o " + path("out.ply")), "nan.xyz", ":2");
  write("inf.wkt", "POINT (0 0)\nPOINT (inf 0)\n");
  expect_bad(*this, run("triangulate " + path("inf.wkt") + " -o " + path("out.ply")), "inf.wkt", ":2");
}

TEST_F(Cli, UnknownExtensionEmptyAndMissingInputs) {
  write("x.dxf", "0\nSECTION\n");
  expect_bad(*this, run("triangulate " + path("x.dxf") + " -o " + path("out.ply")), "x.dxf", "");
  write("empty.xyz", "");
  expect_bad(*this, run("triangulate " + path("empty.xyz") + " -o " + path("out.ply")), "empty.xyz", "");
  expect_bad(*this, run("triangulate " + path("nope.shp") + " -o " + path("out.ply")), "nope.shp", "");
}

TEST_F(Cli, UnknownOutputFormatIsAUsageError) {
  write_terrain();
  Result r = run("triangulate " + path("dem.csv") + " -o " + path("out.stl"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(files_matching("out"), 0u);
}

// OBJ and PLY files are begun while the triangulation runs (io/mesh_file_ahead: the vertices first, the faces
// and PLY's header at the end); their bytes are those written in one go (to stdout), and where the vertices or
// the header's length turn out otherwise (crossings add vertices; 8 points on a circle have 6 triangles, not
// the 11 whose digits PLY's header was given) the file is written again, or not begun (a boundary may drop
// vertices). OBJ names no counts.
TEST_F(Cli, AMeshFileBegunAheadHasTheBytesWrittenInOneGo) {
  write_terrain();
  write("cross.wkt", "LINESTRING (500010 6000010, 500180 6000170)\nLINESTRING (500010 6000170, 500180 6000010)\n");
  std::string octagon;
  for (int k = 0; k < 8; ++k)
    octagon += std::to_string(100 * std::cos(k * M_PI / 4)) + " " + std::to_string(100 * std::sin(k * M_PI / 4)) +
               " 1\n";
  write("octagon.xyz", octagon);
  write("ring.wkt", "POLYGON ((500050 6000050, 500150 6000050, 500150 6000150, 500050 6000150, 500050 6000050))\n");
  struct Case {
    std::string inputs, expect;  // expect: what the -v log says of the file begun ahead
  };
  const std::vector<Case> cases = {
      {path("dem.csv") + " " + path("lines.wkt"), "finished"},
      {path("dem.csv") + " " + path("cross.wkt"), "written again"},
      {path("octagon.xyz") + " --crs none", "written again"},
      {path("dem.csv") + " " + path("ring.wkt") + ":role=boundary", ""},
  };
  for (const Case& c : cases)
    for (const std::string format : {"ply", "ply --ascii", "obj"}) {
      const std::string name = format.substr(0, 3);
      const std::string what = c.inputs + " / " + format;
      Result r = run("-v triangulate " + c.inputs + " --backend cgal -o " + path("ahead." + name) +
                     (format.size() > 3 ? " --ascii" : ""));
      ASSERT_EQ(r.code, 0) << what << ": " << r.err;
      const bool header_only = c.inputs.find("octagon") != std::string::npos && name == "obj";
      if (c.expect.empty())
        EXPECT_EQ(r.err.find("written ahead"), std::string::npos) << what;
      else
        EXPECT_NE(r.err.find(header_only ? "finished" : c.expect), std::string::npos) << what << ": " << r.err;
      r = run("triangulate " + c.inputs + " --backend cgal -q --format " + format + " -o -", path("one." + name));
      ASSERT_EQ(r.code, 0) << what << ": " << r.err;
      EXPECT_TRUE(slurp(path("ahead." + name)) == slurp(path("one." + name))) << what;
      EXPECT_EQ(files_matching("ahead." + name + ".tmp"), 0u) << what;
    }
}

TEST_F(Cli, FailedRunKeepsTheOldOutput) {
  write_terrain();
  ASSERT_EQ(run("triangulate " + path("dem.csv") + " -q -o " + path("keep.ply")).code, 0);
  std::string before = slurp(path("keep.ply"));
  write("bad.wkt", "POLYGON ((0 0, 1 0, 1 1\n");
  Result r = run("triangulate " + path("bad.wkt") + " -o " + path("keep.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(slurp(path("keep.ply")), before);
  EXPECT_EQ(files_matching("keep"), 1u) << "temporary file left behind";
}

}  // namespace

namespace {

TEST_F(Cli, LandXmlAnd2dmAreWrittenAndPassVerify) {
  write_terrain();
  for (std::string ext : {"xml", "2dm"}) {
    std::string out = path("tin." + ext);
    Result r = run("triangulate " + path("dem.csv") + " " + path("lines.wkt") + " --backend cgal -q -o " + out);
    ASSERT_EQ(r.code, 0) << r.err;
    Result v = run("verify " + out + " " + path("dem.csv") + " " + path("lines.wkt"));
    EXPECT_EQ(v.code, 0) << ext << ": " << v.err;
  }
  EXPECT_EQ(slurp(path("tin.2dm")).rfind("MESH2D\n", 0), 0u);
  EXPECT_NE(slurp(path("tin.xml")).find("<Definition surfType=\"TIN\">"), std::string::npos);
  // LandXML carries a date and time; SOURCE_DATE_EPOCH fixes them, so the same input gives the same bytes.
  std::string args = "triangulate " + path("dem.csv") + " --backend cgal -q -o ";
  ASSERT_EQ(run(args + path("a.xml")).code, 0);
  ASSERT_EQ(std::system(("SOURCE_DATE_EPOCH=1700000000 " + std::string(CDTGPU_BINARY) + " " + args + path("b.xml") +
                         " && SOURCE_DATE_EPOCH=1700000000 " + std::string(CDTGPU_BINARY) + " " + args + path("c.xml"))
                            .c_str()),
            0);
  EXPECT_EQ(slurp(path("b.xml")), slurp(path("c.xml")));
  EXPECT_NE(slurp(path("b.xml")).find("date=\"2023-11-14\" time=\"22:13:20\""), std::string::npos);
}

TEST_F(Cli, GridContoursAndPreviewComeWithTheMeshInOneRun) {
  // Lon/lat input, so the CRS has a WKT and every output gets its .prj.
  write("ll.xyz", "150.30 -33.70 1000\n150.32 -33.70 1010\n150.31 -33.72 1005\n150.31 -33.69 990\n150.305 -33.705 1021\n");
  Result r = run("triangulate " + path("ll.xyz") + " --backend cgal -q -o " + path("tin.ply") + " --grid-out " +
                 path("dem.asc") + " --cell 50 --contours-out " + path("lines.wkt") + " --interval 5 --preview " +
                 path("tin.png") + " --stats " + path("s.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"tin.ply", "tin.prj", "dem.asc", "dem.prj", "lines.wkt", "lines.prj", "tin.png"})
    EXPECT_TRUE(fs::exists(path(f))) << f;
  EXPECT_EQ(slurp(path("tin.png")).rfind("\x89PNG\r\n\x1a\n", 0), 0u);
  const std::string asc = slurp(path("dem.asc"));
  EXPECT_EQ(asc.rfind("ncols ", 0), 0u) << asc.substr(0, 200);
  EXPECT_NE(asc.find("\ncellsize 50\nNODATA_value -9999\n"), std::string::npos) << asc.substr(0, 200);
  const std::string wkt = slurp(path("lines.wkt"));
  EXPECT_EQ(wkt.rfind("LINESTRING Z (", 0), 0u) << wkt.substr(0, 200);
  EXPECT_NE(wkt.find(" 995, "), std::string::npos);
  const auto stats = nlohmann::json::parse(slurp(path("s.json")));
  EXPECT_EQ(stats["counts"]["contour_lines"], size_t(std::count(wkt.begin(), wkt.end(), '\n')));
  EXPECT_GT(stats["counts"]["grid_cells"].get<uint64_t>(), 100u);
  for (const char* stage : {"grid", "contours", "preview", "write"})
    EXPECT_TRUE(stats["stage_ms"].contains(stage)) << stage;
  // The grid is an input cdtgpu reads again.
  Result again = run("triangulate " + path("dem.asc") + " --backend cgal -q -o " + path("again.obj"));
  EXPECT_EQ(again.code, 0) << again.err;
}

// With the GPU backend the grid, the preview's grid and the contours are made on the GPU (gpu/raster,
// gpu/contours): the files are the CPU's byte for byte, boundary and hole included (NODATA outside and in
// the lake), and --stats has their device times.
TEST_F(Cli, GridPreviewAndContoursOfTheGpuBackendAreTheCpusBytes) {
  write_terrain();
  write("area.wkt", "POLYGON ((500030 6000030, 500170 6000030, 500170 6000170, 500030 6000170, 500030 6000030))\n");
  write("lake.wkt", "POLYGON ((500060 6000060, 500090 6000060, 500090 6000090, 500060 6000090, 500060 6000060))\n");
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " " + path("area.wkt") + ":role=boundary " +
                         path("lake.wkt") + ":role=hole --crs none -q";
  for (const std::string b : {"cgal", "gpu"}) {
    Result r = run("triangulate " + in + " --backend " + b + " -o " + path(b + ".ply") + " --grid-out " +
                   path(b + ".asc") + " --cell 0.5 --contours-out " + path(b + ".geojson") + " --interval 0.5" +
                   " --preview " + path(b + ".png") + " --stats " + path(b + ".json"));
    ASSERT_EQ(r.code, 0) << b << ": " << r.err;
  }
  for (const char* ext : {".ply", ".asc", ".geojson", ".png"})
    EXPECT_TRUE(slurp(path(std::string("gpu") + ext)) == slurp(path(std::string("cgal") + ext))) << ext;
  const auto stats = nlohmann::json::parse(slurp(path("gpu.json")));
  EXPECT_EQ(stats["backend"], "gpu");
  for (const char* stage : {"grid", "contours", "preview"})
    EXPECT_TRUE(stats["gpu_stage_ms"].contains(stage)) << stage;
  const std::string asc = slurp(path("gpu.asc"));
  EXPECT_GT(std::count(asc.begin(), asc.end(), '-'), 1000) << "NODATA outside the boundary and in the lake";
}

TEST_F(Cli, LandXmlAnd2dmGoToStdout) {
  write("pts.wkt", "MULTIPOINT ((0 0), (1 0), (0 1), (1 1))\n");
  Result r = run("triangulate " + path("pts.wkt") + " --crs none --backend cgal -q --format landxml -o -", path("o.xml"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(path("o.xml")).find("<P id=\"4\">1 1 0</P>"), std::string::npos) << slurp(path("o.xml"));
  r = run("triangulate " + path("pts.wkt") + " --crs none --backend cgal -q --format 2dm -o -", path("o.2dm"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(path("o.2dm")).find("\nND 4 1 1 0\nE3T 1 "), std::string::npos) << slurp(path("o.2dm"));
}

TEST_F(Cli, AGridTooFineOrABadCellIsAUsageErrorAndWritesNothing) {
  write_terrain();
  for (std::string bad : {"--cell 0", "--cell -2", "--cell 0.0001", "--cell x"}) {
    Result r = run("triangulate " + path("dem.csv") + " --backend cgal -o " + path("out.ply") + " --grid-out " +
                   path("out.asc") + " " + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.err;
    EXPECT_EQ(files_matching("out"), 0u) << bad;
  }
  Result r = run("triangulate " + path("dem.csv") + " --backend cgal -o " + path("out.ply") + " --contours-out " +
                 path("out.wkt") + " --interval 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(files_matching("out"), 0u);
}

}  // namespace

// GPU tiles check their own constraints and begin before any resolve; here they find lines through grid vertices
// and two lines that cross, so the input is resolved (taken from the prepared input: nothing reads it later)
// and tiled again; the tile device and its staging were opened before prepare. The same bytes as the CPU's single
// run.
TEST_F(Cli, GpuTilesOfAnInputToSplitGiveTheSingleRunsBytes) {
  write("dem.csv", cdtgpu::test::grid_dem_csv(40));
  write("lines.wkt",
        "LINESTRING Z (500000 6000000 100, 500030 6000030 130)\n"          // through 29 grid vertices
        "LINESTRING Z (500000.5 6000010.5 100, 500030.5 6000020.5 101)\n"  // these two cross
        "LINESTRING Z (500000.5 6000020.5 102, 500030.5 6000010.5 103)\n");
  const std::string in = path("dem.csv") + " " + path("lines.wkt");
  Result r = run("triangulate " + in + " --backend cgal --max-tile-points 0 -q -o " + path("single.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = run("-v triangulate " + in + " --backend gpu --max-tile-points 200 -o " + path("tiled.ply") + " --stats " +
          path("tiled.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("resolved, then tiled again"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("opened before prepare"), std::string::npos) << r.err;  // open_tiles_early
  EXPECT_TRUE(slurp(path("tiled.ply")) == slurp(path("single.ply")));
  const auto stats = nlohmann::json::parse(slurp(path("tiled.json")));
  EXPECT_GE(stats["counts"]["tiles"].get<int>(), 2);
}

// Contours on a lattice that cross beside T-junctions: (7,6)-(9,7) crosses (10,5)-(7,7), and (8,6)-(11,9) passes
// exactly through (9,7). The default backend for so small an input is the CPU's single run, which was CGAL's own
// crossing handling and segfaulted here (CGAL 5.5.1); now every backend and tiling writes one mesh.
TEST_F(Cli, LatticeCrossingsBesideTJunctionsGiveOneMeshOnEveryBackend) {
  std::string dem;
  for (int i = 0; i <= 14; ++i)
    for (int j = 0; j <= 14; ++j)
      dem += std::to_string(i) + " " + std::to_string(j) + " " + std::to_string((i * j) % 7) + "\n";
  write("dem.xyz", dem);
  write("lines.wkt",
        "LINESTRING Z (11 9 5, 9 7 5, 7 6 5, 9 7 5, 10 10 5, 11 9 5, 9 11 5, 6 9 5)\n"
        "LINESTRING Z (10 5 5, 7 7 5, 5 7 5, 3 10 5)\n"
        "LINESTRING Z (7 3 5, 7 1 5, 8 3 5, 5 3 5, 8 6 5, 11 9 5)\n");
  const std::string in = path("dem.xyz") + " " + path("lines.wkt") + " --crs none -q";
  Result r = run("triangulate " + in + " -o " + path("auto.ply") + " --stats " + path("auto.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto stats = nlohmann::json::parse(slurp(path("auto.json")));
  EXPECT_EQ(stats["backend"], "cgal");
  EXPECT_GT(stats["counts"]["steiner_points"].get<int>(), 0);
  r = run("verify " + path("auto.ply") + " " + path("dem.xyz") + " " + path("lines.wkt") + " --crs none");
  EXPECT_EQ(r.code, 0) << r.err;
  const bool gpu = !first_usable_device().empty();
  for (const std::string how :
       {"--backend cgal --max-tile-points 16", "--backend gpu", "--backend gpu --max-tile-points 40"}) {
    if (!gpu && how.find("gpu") != std::string::npos) continue;
    r = run("triangulate " + in + " " + how + " -o " + path("other.ply"));
    ASSERT_EQ(r.code, 0) << how << ": " << r.err;
    EXPECT_TRUE(slurp(path("other.ply")) == slurp(path("auto.ply"))) << how;
  }
}

// Segments through vertices and none crossing (a contour through DEM points, footprints sharing a wall): GPU tiles
// split them themselves, no resolve runs, and the bytes and the count of splits are the untiled run's.
TEST_F(Cli, GpuTilesSplitSegmentsThroughVerticesThemselves) {
  write("dem.csv", cdtgpu::test::grid_dem_csv(40));
  write("lines.wkt",
        "LINESTRING Z (500000 6000000 100, 500030 6000030 130)\n"  // through 29 grid vertices
        "POLYGON Z ((500002 6000032 1, 500020 6000032 1, 500020 6000038 1, 500002 6000038 1, 500002 6000032 1))\n"
        "POLYGON Z ((500010 6000038 2, 500036 6000038 2, 500036 6000039 2, 500010 6000039 2, 500010 6000038 2))\n");
  const std::string in = path("dem.csv") + " " + path("lines.wkt");
  Result r = run("triangulate " + in + " --backend gpu --max-tile-points 0 -q -o " + path("single.ply") + " --stats " +
                 path("single.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  r = run("-v triangulate " + in + " --backend gpu --max-tile-points 200 -o " + path("tiled.ply") + " --stats " +
          path("tiled.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("resolved, then tiled again"), std::string::npos) << r.err;
  EXPECT_TRUE(slurp(path("tiled.ply")) == slurp(path("single.ply")));
  const auto single = nlohmann::json::parse(slurp(path("single.json")));
  const auto tiled = nlohmann::json::parse(slurp(path("tiled.json")));
  EXPECT_GE(tiled["counts"]["tiles"].get<int>(), 2);
  EXPECT_GT(single["counts"]["constraint_splits_at_vertices"].get<int>(), 29);
  EXPECT_EQ(tiled["counts"]["constraint_splits_at_vertices"], single["counts"]["constraint_splits_at_vertices"]);
}

// --max-tile-points: tiny tiles give the untiled run's bytes on both backends, with roles, draping, --max-edge,
// the grid, contours and preview; --stats has the same counts plus the tiles'.
TEST_F(Cli, TiledRunsWriteTheUntiledBytes) {
  write_terrain();
  write("area.wkt", "POLYGON ((500030 6000030, 500170 6000030, 500170 6000170, 500030 6000170, 500030 6000030))\n");
  write("lake.wkt", "POLYGON ((500060 6000060, 500090 6000060, 500090 6000090, 500060 6000090, 500060 6000060))\n");
  write("house.wkt", "POLYGON ((500150.5 6000100.5, 500160.5 6000100.5, 500160.5 6000110.5, 500150.5 6000110.5))\n");
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " " + path("area.wkt") + ":role=boundary " +
                         path("lake.wkt") + ":role=hole " + path("house.wkt") + ":z=drape --max-edge 40 -q";
  auto outputs = [&](const std::string& name) {
    return " -o " + path(name + ".ply") + " --grid-out " + path(name + ".asc") + " --cell 0.5 --contours-out " +
           path(name + ".wkt") + " --interval 0.5 --preview " + path(name + ".png") + " --stats " +
           path(name + ".json");
  };
  Result r = run("triangulate " + in + " --backend cgal --max-tile-points 0" + outputs("single"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto single = nlohmann::json::parse(slurp(path("single.json")));
  EXPECT_FALSE(single["counts"].contains("tiles"));
  for (const std::string backend : {"cgal", "gpu"})
    for (const std::string tile : {"16", "50", "300"}) {
      const std::string name = backend + tile;
      r = run("triangulate " + in + " --backend " + backend + " --max-tile-points " + tile + outputs(name));
      ASSERT_EQ(r.code, 0) << name << ": " << r.err;
      for (const char* ext : {".ply", ".asc", ".wkt", ".png"})
        EXPECT_TRUE(slurp(path(name + ext)) == slurp(path(std::string("single") + ext))) << name << ext;
      auto stats = nlohmann::json::parse(slurp(path(name + ".json")));
      EXPECT_GE(stats["counts"]["tiles"].get<int>(), 2) << name;
      EXPECT_GT(stats["counts"]["merge_vertices"].get<int>(), 0) << name;
      for (const char* key : {"tile_points", "tiles", "tile_levels", "tile_final_triangles", "tile_devices", "merge_vertices",
                              "merge_segments", "merge_triangles", "constraint_splits_at_vertices",
                              "gpu_delaunay_rounds", "gpu_delaunay_built_twice", "gpu_constraint_flip_rounds",
                              "gpu_legalise_rounds", "gpu_peak_device_bytes", "gpu_tile_retries"})
        stats["counts"].erase(key);
      EXPECT_EQ(stats["counts"], single["counts"]) << name;
    }
}

// The bundled sample (real contours, DEM points and building footprints) tiled: the untiled bytes.
TEST_F(Cli, TiledSampleIsTheUntiledSample) {
  const std::string s = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  const std::string inputs = s + "contours.shp:z=ELEV " + s + "dem.xyz " + s + "buildings.shp:z=min --backend cgal";
  const std::string in = inputs + " -q";
  ASSERT_EQ(run("triangulate " + in + " --max-tile-points 0 -o " + path("single.ply")).code, 0);
  Result r = run("triangulate " + in + " --max-tile-points 400 -o " + path("tiled.ply") + " --stats " +
                 path("t.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(slurp(path("tiled.ply")) == slurp(path("single.ply")));
  EXPECT_GE(nlohmann::json::parse(slurp(path("t.json")))["counts"]["tiles"].get<int>(), 8);
  // The tiled run only writes its mesh, in every OBJ and PLY form and to stdout; the counts are the mesh's. Its
  // tiles are the CPU's squares, whose runs interleave everywhere: the order is copied into one array, not left
  // in the runs (TileOptions::in_runs is for slabs: gpu_tiles_test; the writers' spans: writers_test).
  struct Form {
    const char* format;
    bool to_stdout;
  };
  for (const Form f : {Form{"obj", false}, Form{"ply --ascii", false}, Form{"ply", true}}) {
    std::string log;
    auto triangulate = [&](const std::string& tiles, const std::string& name) {
      const std::string file = path(name);
      const Result got = run("-v triangulate " + inputs + " --max-tile-points " + tiles + " --format " + f.format +
                                 " --stats " + path(name + ".json") + (f.to_stdout ? " -o -" : " -o " + file),
                             f.to_stdout ? file : "/dev/null");
      EXPECT_EQ(got.code, 0) << f.format << ": " << got.err;
      log = got.err;
      return slurp(file);
    };
    const std::string one = triangulate("0", "one"), tiled = triangulate("400", "tiled");
    EXPECT_NE(log.find("tiles, level 1: the merge's triangles kept in"), std::string::npos) << f.format << ": " << log;
    EXPECT_EQ(log.find("canonical order left in the runs"), std::string::npos) << f.format << ": " << log;
    EXPECT_FALSE(tiled.empty()) << f.format;
    EXPECT_TRUE(tiled == one) << f.format;
    const auto counts = [&](const char* name) {
      return nlohmann::json::parse(slurp(path(std::string(name) + ".json")))["counts"];
    };
    EXPECT_EQ(counts("tiled")["triangles"], counts("one")["triangles"]) << f.format;
    EXPECT_GE(counts("tiled")["tiles"].get<int>(), 8) << f.format;
  }
}

// The folder of new tiles that a killed run left (`tiles.tmp-<pid>`, nobody holding it) goes when the folder is
// written again; one that a run holds (locked, as every run holds its own until the rename) stays.
TEST_F(Cli, AKilledRunsTilesFolderGoesAndAHeldOneStays) {
  write_terrain();
  for (const char* d : {"tiles.tmp-4000003", "tiles.tmp-4000004", "tiles.tmp-x"}) {
    fs::create_directories(path(d));
    write(std::string(d) + "/tile_0001.ply", "a partial tile\n");
  }
  const int fd = ::open(path("tiles.tmp-4000004").c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  const Result r = run("triangulate " + path("dem.csv") + " " + path("lines.wkt") +
                       " --backend cgal --max-tile-points 60 --tiles-out " + path("tiles"));
  ::close(fd);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("tiles/index.geojson")));
  EXPECT_FALSE(fs::exists(path("tiles.tmp-4000003"))) << r.err;
  EXPECT_NE(r.err.find("the tiles of an earlier run that was killed"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(path("tiles.tmp-4000004/tile_0001.ply"))) << "held by a run: left alone";
  EXPECT_TRUE(fs::exists(path("tiles.tmp-x/tile_0001.ply"))) << "not a name of ours";
}

// A batch reads an output folder's names once (io/atomic_file, remove_killed_runs_temps): every job's target
// still loses what killed runs left beside it, a held one stays, and a file removed is not tried again.
TEST_F(Cli, ABatchRemovesKilledRunsTempsBesideEachOfItsOutputs) {
  write_terrain();
  for (const char* f : {"a.ply.tmp-4000021", "b.ply.tmp-4000022", "b.ply.tmp-4000023", "b.ply.tmp-x"})
    write(f, "a partial output\n");
  const int fd = ::open(path("b.ply.tmp-4000023").c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " --backend cgal -o ";
  write("jobs.txt", in + path("a.ply") + "\n" + in + path("b.ply") + "\n" + in + path("b.ply") + "\n");
  const Result r = run("batch " + path("jobs.txt"));
  ::close(fd);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("a.ply")) && fs::exists(path("b.ply")));
  EXPECT_FALSE(fs::exists(path("a.ply.tmp-4000021"))) << r.err;
  EXPECT_FALSE(fs::exists(path("b.ply.tmp-4000022"))) << r.err;
  EXPECT_TRUE(fs::exists(path("b.ply.tmp-4000023"))) << "held by a run: left alone";
  EXPECT_TRUE(fs::exists(path("b.ply.tmp-x"))) << "not a name of ours";
  const std::string said = "b.ply.tmp-4000022 (";
  ASSERT_NE(r.err.find(said), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(said, r.err.find(said) + 1), std::string::npos) << "said once: " << r.err;
}

// A run killed between --tiles-out's two renames leaves the tiles it replaced as DIR.old-<pid> (and maybe no
// DIR): a run that fails leaves them (maybe the only copy), one that puts its own tiles in place removes them.
TEST_F(Cli, TheTilesAKilledRunReplacedGoOnceNewTilesAreInPlace) {
  write_terrain();
  for (const char* d : {"tiles.old-4000005", "tiles.old-x"}) {
    fs::create_directories(path(d));
    write(std::string(d) + "/tile_0001.ply", "an old tile\n");
  }
  write("bad.csv", "x,y,z\n1,2,3\n1,oops,3\n");
  Result r = run("triangulate " + path("bad.csv") + " --backend cgal --max-tile-points 60 --tiles-out " +
                 path("tiles"));
  EXPECT_NE(r.code, 0);
  EXPECT_TRUE(fs::exists(path("tiles.old-4000005/tile_0001.ply"))) << "a failed run leaves them";
  r = run("triangulate " + path("dem.csv") + " " + path("lines.wkt") +
          " --backend cgal --max-tile-points 60 --tiles-out " + path("tiles"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("tiles/index.geojson")));
  EXPECT_FALSE(fs::exists(path("tiles.old-4000005"))) << r.err;
  EXPECT_NE(r.err.find("the tiles it replaced of an earlier run that was killed"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(path("tiles.old-x/tile_0001.ply"))) << "not a name of ours";
}

// --tiles-out: the union of the tile files is the mesh of -o, each triangle in exactly one file; verify accepts
// the folder and refuses it with a file missing or a triangle in two files.
TEST_F(Cli, TilesOutFolderIsTheMeshInPieces) {
  write_terrain();
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " -q --backend cgal";
  Result r = run("triangulate " + in + " --max-tile-points 60 --tiles-out " + path("tiles/") + " -o " +
                 path("single.ply") + " --stats " + path("s.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto index = nlohmann::json::parse(slurp(path("tiles/index.geojson")));
  ASSERT_GE(index["features"].size(), 4u);
  EXPECT_EQ(nlohmann::json::parse(slurp(path("s.json")))["counts"]["tile_files"], index["features"].size());
  const cdtgpu::Mesh whole = cdtgpu::read_tiles_dir(path("tiles"));
  const cdtgpu::Mesh single = cdtgpu::read_mesh_file(path("single.ply"));
  EXPECT_EQ(whole.vertices, single.vertices);
  EXPECT_TRUE(whole.triangles == single.triangles);
  size_t triangles = 0;
  for (const auto& f : index["features"]) triangles += f["properties"]["triangles"].get<size_t>();
  EXPECT_EQ(triangles, single.triangles.size()) << "every triangle in exactly one file";
  EXPECT_EQ(run("verify " + path("tiles") + " " + path("dem.csv") + " " + path("lines.wkt")).code, 0);

  // Only --tiles-out, as OBJ, written again over the old folder.
  r = run("triangulate " + in + " --max-tile-points 100 --format obj --tiles-out " + path("tiles"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("tiles/tile_0001.obj")));
  EXPECT_FALSE(fs::exists(path("tiles/tile_0001.ply"))) << "the old folder's files are gone";
  EXPECT_TRUE(cdtgpu::read_tiles_dir(path("tiles")).triangles == single.triangles);

  // The index naming one file twice: its triangles would count twice.
  const std::string good_index = slurp(path("tiles/index.geojson"));
  auto twice = nlohmann::json::parse(good_index);
  twice["features"][1]["properties"] = twice["features"][0]["properties"];
  write("tiles/index.geojson", twice.dump());
  Result v = run("verify " + path("tiles") + " " + path("dem.csv") + " " + path("lines.wkt"));
  EXPECT_EQ(v.code, 2) << v.err;
  EXPECT_NE(v.err.find("a triangle is in two tile files"), std::string::npos) << v.err;
  write("tiles/index.geojson", good_index);
  fs::remove(path("tiles/tile_0002.obj"));
  v = run("verify " + path("tiles") + " " + path("dem.csv") + " " + path("lines.wkt"));
  EXPECT_EQ(v.code, 2) << v.err;
  EXPECT_NE(v.err.find("tile_0002.obj"), std::string::npos) << v.err;
  EXPECT_EQ(run("triangulate " + in).code, 2) << "no output at all is a usage error";
}

// A tile the device cannot take: a forced GPU run fails with exit 3 naming the tile and writes nothing; auto
// falls back to CPU tiles with the same bytes.
TEST_F(Cli, ATileTheDeviceRefusesFailsOrFallsBack) {
  write_terrain();
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " -q --max-tile-points 50";
  const std::string device = first_usable_device();
  ASSERT_FALSE(device.empty());
  ASSERT_EQ(run("triangulate " + in + " --backend cgal -o " + path("cgal.ply")).code, 0);
  ::setenv("CDTGPU_AUTO_MIN_POINTS", "1", 1);
  ::setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "64K", 1);
  Result forced = run("triangulate " + in + " --backend gpu -o " + path("forced.ply"));
  Result fell = run("triangulate " + in + " --device '" + device + "' -o " + path("auto.ply") + " --stats " +
                    path("auto.json"));
  ::unsetenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  ::unsetenv("CDTGPU_AUTO_MIN_POINTS");
  EXPECT_EQ(forced.code, 3) << forced.err;
  EXPECT_NE(forced.err.find(", level 1 ("), std::string::npos) << "names the tile: " << forced.err;
  EXPECT_FALSE(fs::exists(path("forced.ply")));
  ASSERT_EQ(fell.code, 0) << fell.err;
  const auto stats = nlohmann::json::parse(slurp(path("auto.json")));
  EXPECT_EQ(stats["backend"], "cgal");
  EXPECT_GE(stats["counts"]["tiles"].get<int>(), 2);
  EXPECT_EQ(slurp(path("auto.ply")), slurp(path("cgal.ply")));
}

// A tile more than its device holds (here its memory, CDTGPU_DEVICE_MEMORY_LIMIT; on the H100 machine the
// intersected-edge table of 20M breakline segments over 104M LiDAR points) is not the end of the GPU run: the
// tiling starts again with smaller tiles, still within --max-tile-points, and gives the same bytes. So does a
// whole input the device cannot take in one piece, unless --max-tile-points 0 forbids tiles.
TEST_F(Cli, TilesTooLargeForTheDeviceAreMadeSmaller) {
  std::ostringstream xyz, wkt;
  xyz << std::fixed << std::setprecision(2);
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 100; ++j)
      xyz << 500000 + 2 * i + (i * 7 + j * 13) % 50 * 0.01 << ' ' << 6000000 + 2 * j + (i * 11 + j * 3) % 50 * 0.01
          << ' ' << (i + j) % 10 << '\n';
  for (int k = 0; k < 6; ++k)
    wkt << "LINESTRING Z (500001 " << 6000010 + 30 * k << " 5, 500120 " << 6000017 + 30 * k << " 5, 500239 "
        << 6000010 + 30 * k << " 5)\n";
  write("dense.xyz", xyz.str());
  write("breaklines.wkt", wkt.str());
  const std::string whole = path("dense.xyz") + " " + path("breaklines.wkt");
  const std::string in = whole + " --max-tile-points 6000";
  const std::string device = first_usable_device();
  ASSERT_FALSE(device.empty());
  ASSERT_EQ(run("triangulate " + in + " -q --backend cgal -o " + path("cgal.ply")).code, 0);
  const std::string gpu = " --backend gpu --device '" + device + "'";
  ::setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "1M", 1);
  const Result r = run("triangulate " + in + gpu + " -o " + path("gpu.ply") + " --stats " + path("gpu.json"));
  // Untiled first (the input is far below the device's tile): the whole is too large, its tiles are not.
  const Result untiled = run("triangulate " + whole + gpu + " -q -o " + path("whole.ply") + " --stats " +
                             path("whole.json"));
  const Result never = run("triangulate " + whole + gpu + " -q --max-tile-points 0 -o " + path("never.ply"));
  ::unsetenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  ASSERT_EQ(untiled.code, 0) << untiled.err;
  EXPECT_NE(untiled.err.find("again in tiles of at most"), std::string::npos) << untiled.err;
  const auto whole_stats = nlohmann::json::parse(slurp(path("whole.json")));
  EXPECT_GE(whole_stats["counts"]["tiles"].get<uint64_t>(), 2u);
  EXPECT_GE(whole_stats["counts"]["gpu_tile_retries"].get<uint64_t>(), 1u);
  EXPECT_EQ(slurp(path("whole.ply")), slurp(path("cgal.ply")));
  EXPECT_EQ(never.code, 3) << "--max-tile-points 0 never tiles: " << never.err;
  EXPECT_FALSE(fs::exists(path("never.ply")));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find(", level 1 ("), std::string::npos) << "names the tile: " << r.err;
  EXPECT_NE(r.err.find("again in tiles of at most 3000 points"), std::string::npos) << r.err;
  const auto stats = nlohmann::json::parse(slurp(path("gpu.json")));
  EXPECT_EQ(stats["backend"], "gpu");
  EXPECT_GE(stats["counts"]["gpu_tile_retries"].get<uint64_t>(), 1u);
  EXPECT_LT(stats["counts"]["tile_points"].get<uint64_t>(), 6000u);
  EXPECT_EQ(slurp(path("gpu.ply")), slurp(path("cgal.ply")));
}

// Auto with tiles, and a device that may not come (CI's lavapipe does not count for auto): the resolve beside
// the device's start took the prepared input itself, so without a device the CPU tiles what it resolved, and
// with one the device does. The same bytes either way, and the prepared input gone from the peak.
TEST_F(Cli, AutoTiledRunsTileWhatTheResolveMadeWithOrWithoutADevice) {
  write_terrain();
  const std::string in = path("dem.csv") + " " + path("lines.wkt") + " -q --max-tile-points 50";
  ASSERT_EQ(run("triangulate " + in + " --backend cgal -o " + path("cgal.ply")).code, 0);
  ::setenv("CDTGPU_AUTO_MIN_POINTS", "1", 1);
  const Result r = run("triangulate " + in + " -o " + path("auto.ply") + " --stats " + path("auto.json"));
  ::unsetenv("CDTGPU_AUTO_MIN_POINTS");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto stats = nlohmann::json::parse(slurp(path("auto.json")));
  if (stats["backend"] == "cgal") {
    EXPECT_EQ(stats["backend_reason"].get<std::string>().rfind("no GPU to use", 0), 0u) << stats["backend_reason"];
  }
  EXPECT_GE(stats["counts"]["tiles"].get<int>(), 2);
  EXPECT_GT(stats["counts"]["constraints"].get<int>(), 0);
  EXPECT_EQ(slurp(path("auto.ply")), slurp(path("cgal.ply")));
}

// Messages say what is allowed in words and write numbers as read; a coordinate far outside any CRS is refused
// naming the file and line.
TEST_F(Cli, RangeErrorsAndFarCoordinatesAreClearMessages) {
  write_terrain();
  Result r = run("triangulate " + path("dem.csv") + " -o " + path("t.ply") + " --max-edge -5");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--max-edge: must be a number greater than 0, not -5"), std::string::npos) << r.err;
  EXPECT_LT(r.err.size(), 200u) << r.err;
  r = run("triangulate " + path("dem.csv") + " -o " + path("t.ply") + " --max-tile-points -1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("must be 0 or more, not -1"), std::string::npos) << r.err;
  r = run("triangulate " + path("dem.csv") + " -o " + path("t.ply") + " --grid-out " + path("g.asc") + " --cell 1e-9");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cell size 1e-09 would have"), std::string::npos) << r.err;
  write("far.xyz", "500000 6000000 1\n500010 6000000 2\n2e15 6000010 3\n");
  r = run("triangulate " + path("far.xyz") + " --crs none -o " + path("far.ply"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("far.xyz:3: coordinate 2e+15 is beyond"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("far.ply")));
}
