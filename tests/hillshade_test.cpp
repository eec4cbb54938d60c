// The --preview picture (core/hillshade, io/write_png): a plane gets Lambert's shade of its normal
// everywhere, a slope facing the light is brighter than one facing away, NODATA is transparent, and the PNG
// of the sample reads back through libpng at about 1000 pixels on the long side with the grid's pixels.
#include "core/hillshade.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "io/write_png.hpp"
#include "sample_mesh.hpp"

namespace cdtgpu {
namespace {

Mesh plane_mesh(double a, double b) {
  InputSet in;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) in.points.push_back({i * 5.0, j * 5.0, a * i * 5 + b * j * 5});
  return triangulate_cgal(prepare(in)).mesh;
}

TEST(Hillshade, APlaneGetsTheLambertShadeOfItsNormal) {
  const double a = 0.4, b = -0.3;
  const Raster dem = rasterise(plane_mesh(a, b), 1);
  const std::vector<float> s = hillshade(dem);
  const double az = 315 * std::numbers::pi / 180, alt = 45 * std::numbers::pi / 180;
  const double want = (-a * std::sin(az) * std::cos(alt) - b * std::cos(az) * std::cos(alt) + std::sin(alt)) /
                      std::sqrt(a * a + b * b + 1);
  for (size_t i = 0; i < s.size(); ++i) EXPECT_NEAR(s[i], want, 1e-6) << i;
}

TEST(Hillshade, SlopesFacingTheLightAreBrighter) {
  // Rising to the south-east faces the north-west light; rising to the north-west faces away.
  const float toward = hillshade(rasterise(plane_mesh(0.5, -0.5), 1))[0];
  const float away = hillshade(rasterise(plane_mesh(-0.5, 0.5), 1))[0];
  const float flat = hillshade(rasterise(plane_mesh(0, 0), 1))[0];
  EXPECT_GT(toward, flat);
  EXPECT_GT(flat, away);
  EXPECT_NEAR(flat, std::sin(45 * std::numbers::pi / 180), 1e-6);
}

TEST(Hillshade, TheSamplePreviewReadsBackThroughLibpng) {
  const Mesh& m = test::katoomba_mesh();
  const Raster dem = rasterise(m, preview_cell(m, 1000));
  const uint64_t w = dem.spec.ncols, h = dem.spec.nrows;
  EXPECT_GE(std::max(w, h), 1000u);
  EXPECT_LE(std::max(w, h), 1002u);
  const std::vector<uint8_t> rgba = hillshade_rgba(dem);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("cdtgpu_preview_" + std::to_string(::getpid()) + ".png"))
          .string();
  write_png_file(path, w, h, rgba);

  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&image, path.c_str())) << image.message;
  EXPECT_EQ(image.width, w);
  EXPECT_EQ(image.height, h);
  image.format = PNG_FORMAT_RGBA;
  std::vector<uint8_t> back(PNG_IMAGE_SIZE(image));
  ASSERT_TRUE(png_image_finish_read(&image, nullptr, back.data(), 0, nullptr)) << image.message;
  std::filesystem::remove(path);
  EXPECT_EQ(back, rgba);
  uint64_t transparent = 0;
  for (size_t i = 0; i < dem.z.size(); ++i) {
    EXPECT_EQ(back[i * 4 + 3], dem.z[i] == Raster::nodata ? 0 : 255) << i;
    transparent += back[i * 4 + 3] == 0;
  }
  EXPECT_GT(transparent, 0u);
  EXPECT_LT(transparent, dem.z.size() / 5);
}

TEST(Hillshade, EdgesAreDrawnOnTheirPixelsAndClipped) {
  const Raster dem = rasterise(plane_mesh(0.1, 0.1), 1);  // centres 0 .. 100 both ways, row 0 at y = 100
  std::vector<uint8_t> rgba = hillshade_rgba(dem);
  const std::vector<uint8_t> before = rgba;
  const Points v = {{10, 20, 0},  {30, 20, 0}, {50, -500, 0},
                                 {50, 500, 0}, {-9, -9, 0}, {-5, -1, 0}};
  draw_edges(rgba, dem.spec, v, {{0, 1}, {2, 3}, {4, 5}});
  const uint64_t w = dem.spec.ncols;
  auto dark = [&](uint64_t row, uint64_t col) { return rgba[(row * w + col) * 4 + 2] == 90; };
  for (uint64_t col = 10; col <= 30; ++col) EXPECT_TRUE(dark(80, col)) << col;  // y = 20 is row 80
  EXPECT_FALSE(dark(80, 9));
  EXPECT_FALSE(dark(80, 31));
  for (uint64_t row = 0; row < dem.spec.nrows; ++row)
    EXPECT_TRUE(dark(row, 50)) << row;  // clipped, whole column
  size_t changed = 0;
  for (size_t i = 0; i < rgba.size(); i += 4) changed += rgba[i + 2] != before[i + 2];
  EXPECT_EQ(changed, 21u + dem.spec.nrows - 1);  // the two lines cross once; the third is off the picture
}

TEST(Hillshade, ABadPictureSizeIsRefused) {
  EXPECT_THROW(write_png_file("/nonexistent/x.png", 0, 1, {}), std::runtime_error);
  EXPECT_THROW(write_png_file("/nonexistent/x.png", 2, 2, std::vector<uint8_t>(3)), std::runtime_error);
}

}  // namespace
}  // namespace cdtgpu
