// GPU tiles on several devices (gpu/devices, gpu/tile_triangulator): two contexts on the test machine's device
// (lavapipe in CI) stand for two GPUs. The tiled mesh equals the single CGAL run's whatever device takes which
// tile; --devices lists are checked; a device that fails a tile is named.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/tiles.hpp"
#include "core/workloads.hpp"
#include "gpu/check.hpp"
#include "gpu/devices.hpp"
#include "gpu/tile_triangulator.hpp"

namespace cdtgpu {
namespace {

size_t test_device() { return gpu::pick_device(gpu::list_devices(), ""); }

TEST(GpuTiles, TwoDevicesGiveTheSingleRunsBytes) {
  InputSet in = uniform_points(20000, 7);
  add_dt_edge_constraints(in, 5000, 0.5, 7);
  const PreparedInput p = prepare(in);
  const CdtResult single = triangulate_cgal(p);
  const size_t d = test_device();
  const auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
  for (unsigned in_flight : {2u, 4u}) {
    TileOptions opt;
    opt.max_tile_points = 2500;
    opt.tiles_in_flight = in_flight;
    TileStats ts;
    gpu::GpuCdtStats sum;
    const CdtResult tiled =
        triangulate_tiled(resolve_constraints(p), opt, gpu::gpu_tile_triangulator({&a, &b}, &sum), &ts);
    EXPECT_GE(ts.tiles, 8u);
    EXPECT_GT(sum.wall_total_ms, 0.0);
    EXPECT_EQ(tiled.mesh.vertices, single.mesh.vertices) << in_flight << " in flight";
    EXPECT_TRUE(tiled.mesh.triangles == single.mesh.triangles) << in_flight << " in flight";
  }
}

TEST(GpuTiles, DeviceListsAreChecked) {
  const std::vector<gpu::DeviceInfo> devices = gpu::list_devices();
  const size_t d = test_device();
  const std::vector<size_t> all = gpu::select_devices(devices, "all");
  ASSERT_FALSE(all.empty());
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  EXPECT_EQ(gpu::select_devices(devices, ""), std::vector<size_t>{d});
  EXPECT_EQ(gpu::select_devices(devices, std::to_string(d)), std::vector<size_t>{d});
  auto message = [&](const std::string& spec) {
    try {
      gpu::select_devices(devices, spec);
    } catch (const gpu::DeviceError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message(std::to_string(d) + "," + std::to_string(d)).find("twice"), std::string::npos);
  EXPECT_NE(message("first").find("device indices separated by commas"), std::string::npos);
  EXPECT_NE(message("0,,1").find("device indices separated by commas"), std::string::npos);
  EXPECT_NE(message("99").find("out of range"), std::string::npos);
}

TEST(GpuTiles, AFailingDeviceIsNamed) {
  InputSet in = uniform_points(4000, 3);
  const PreparedInput p = prepare(in);
  const size_t d = test_device();
  setenv("CDTGPU_DEVICE_MEMORY_LIMIT", "64K", 1);  // read when a context is created
  auto ctxs = gpu::create_contexts({d, d}, gpu::ContextOptions{});
  unsetenv("CDTGPU_DEVICE_MEMORY_LIMIT");
  const gpu::GpuCdt a(*ctxs[0]), b(*ctxs[1]);
  TileOptions opt;
  opt.max_tile_points = 1000;
  opt.tiles_in_flight = 4;
  try {
    triangulate_tiled(resolve_constraints(p), opt, gpu::gpu_tile_triangulator({&a, &b}));
    ADD_FAILURE() << "64 KiB of device memory took a tile";
  } catch (const gpu::DeviceError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("on device " + std::to_string(d) + " ("), std::string::npos) << m;
    EXPECT_NE(m.find("vertices"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace cdtgpu
