// Tests of the end-to-end bench: its workload (bench/e2e_workload.hpp) and `cdtgpu bench --table e2e` run
// with cdtgpu as the child (bench/e2e.hpp).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "bench/e2e.hpp"
#include "bench/e2e_workload.hpp"
#include "core/workloads.hpp"
#include "io/readers.hpp"

using namespace cdtgpu;
namespace fs = std::filesystem;

namespace {

class E2eDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cdtgpu_e2e_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

InputSet read_all(const std::vector<std::string>& inputs) {
  InputSet in;
  for (const std::string& p : inputs) read_input(p, {}, in);
  return in;
}

// Geometry only: sources and records name files and lines, which differ between formats.
void expect_same_geometry(const InputSet& a, const InputSet& b) {
  EXPECT_EQ(a.points, b.points);
  ASSERT_EQ(a.lines.size(), b.lines.size());
  for (size_t i = 0; i < a.lines.size(); ++i) {
    EXPECT_EQ(a.lines[i].points, b.lines[i].points) << "line " << i;
    EXPECT_EQ(a.lines[i].closed, b.lines[i].closed) << "line " << i;
  }
  EXPECT_EQ(checksum(a), checksum(b));
}

nlohmann::json read_json(const std::string& path) {
  std::ifstream f(path);
  return nlohmann::json::parse(f);
}

}  // namespace

TEST(E2eWorkload, ContoursAreXMonotoneInDisjointBandsWithExactlyMSegments) {
  for (auto [n, m] :
       {std::pair<uint64_t, uint64_t>{2000, 500}, {2000, 484}, {10, 7}, {4, 1}, {40000, 10000}}) {
    SCOPED_TRACE("n=" + std::to_string(n) + " m=" + std::to_string(m));
    const E2eWorkload w = e2e_workload(n, m, 1);
    EXPECT_EQ(w.input.points.size(), n);
    EXPECT_EQ(w.input.points, uniform_points(n, 1).points);
    const uint64_t k = w.segments_per_line;
    EXPECT_EQ(k, std::max<uint64_t>(2, uint64_t(std::llround(std::sqrt(double(n)) / 2))));
    ASSERT_EQ(w.input.lines.size(), (m + k - 1) / k);
    uint64_t segments = 0;
    double previous_top = -1;
    for (size_t i = 0; i < w.input.lines.size(); ++i) {
      const Polyline& line = w.input.lines[i];
      EXPECT_FALSE(line.closed);
      EXPECT_EQ(line.points.size() - 1,
                i + 1 < w.input.lines.size() ? k : m - (w.input.lines.size() - 1) * k);
      segments += line.points.size() - 1;
      double bottom = line.points[0].y, top = bottom;
      for (size_t j = 0; j < line.points.size(); ++j) {
        const Point3& p = line.points[j];
        if (j) {
          EXPECT_LT(line.points[j - 1].x, p.x) << "line " << i << " is not x-monotone";
        }
        EXPECT_EQ(p.z, 100 + 0.5 * double(i));
        EXPECT_EQ(std::round(p.x * 1000) / 1000, p.x);  // millimetres
        EXPECT_EQ(std::round(p.y * 1000) / 1000, p.y);
        EXPECT_GE(p.x, kUniformX0);
        EXPECT_LT(p.x, kUniformX0 + kUniformSide);
        bottom = std::min(bottom, p.y), top = std::max(top, p.y);
      }
      // Disjoint bands, in order: an x-monotone line entirely above another cannot cross it.
      EXPECT_GT(bottom, previous_top) << "line " << i << " reaches into the band below";
      previous_top = top;
    }
    EXPECT_LT(previous_top, kUniformY0 + kUniformSide);
    EXPECT_EQ(segments, m);
  }
}

TEST_F(E2eDir, TextAndShapefilesReadBackToTheGeneratedInput) {
  const E2eWorkload w = e2e_workload(3000, 750, 7);
  fs::create_directories(dir_ / "text");
  fs::create_directories(dir_ / "shp");
  const E2eFiles text = write_e2e_text(w, path("text"));
  const E2eFiles shp = write_e2e_shapefiles(w, path("shp"));
  ASSERT_EQ(text.inputs.size(), 2u);
  ASSERT_EQ(shp.inputs.size(), 2u);
  EXPECT_EQ(shp.files.size(), 6u);  // .shp .shx .dbf twice
  for (const std::string& f : shp.files) EXPECT_TRUE(fs::exists(f)) << f;
  EXPECT_EQ(text.bytes, fs::file_size(text.inputs[0]) + fs::file_size(text.inputs[1]));

  const InputSet from_text = read_all(text.inputs);
  const InputSet from_shp = read_all(shp.inputs);
  EXPECT_EQ(from_text.repairs.repeated_vertices + from_shp.repairs.repeated_vertices, 0u);
  expect_same_geometry(from_text, w.input);
  expect_same_geometry(from_shp, w.input);
  expect_same_geometry(from_text, from_shp);
}

// LAS holds the points as millimetres: within an ulp of the text's; the DEM's .asc and .tif hold the same cells.
TEST_F(E2eDir, LasAndGridFormatsReadBackToTheirInput) {
  const E2eWorkload w = e2e_workload(3000, 750, 7);
  for (const char* d : {"las", "asc", "tif"}) fs::create_directories(dir_ / d);
  const E2eFiles las = write_e2e_las(w, path("las"));
  const InputSet from_las = read_all(las.inputs);
  ASSERT_EQ(from_las.points.size(), w.input.points.size());
  for (size_t i = 0; i < w.input.points.size(); ++i) {
    const Point3 &a = from_las.points[i], &b = w.input.points[i];
    ASSERT_LE(std::abs(a.x - b.x), 1e-9) << i;
    ASSERT_LE(std::abs(a.y - b.y), 1e-9) << i;
    ASSERT_LE(std::abs(a.z - b.z), 1e-12) << i;
  }
  ASSERT_EQ(from_las.lines.size(), w.input.lines.size());
  EXPECT_EQ(las.bytes, fs::file_size(las.inputs[0]) + fs::file_size(las.inputs[1]));

  const Raster dem = e2e_dem(3000);
  EXPECT_EQ(dem.spec.cell, 183);  // round(10 km / sqrt(3000)) metres
  EXPECT_EQ(dem.z.size(), 54u * 54u);
  const InputSet asc = read_all(write_e2e_grid(w, dem, false, path("asc")).inputs);
  const InputSet tif = read_all(write_e2e_grid(w, dem, true, path("tif")).inputs);
  ASSERT_EQ(asc.points.size(), dem.z.size());
  expect_same_geometry(asc, tif);
  for (size_t row = 0, i = 0; row < dem.spec.nrows; ++row)
    for (size_t col = 0; col < dem.spec.ncols; ++col, ++i)
      ASSERT_EQ(asc.points[i], (Point3{dem.spec.x(col), dem.spec.y(row), dem.at(row, col)})) << row << " " << col;
}

// The LAS and grid rows on a small row: every format's PLYs equal within their kind, the cells counted.
TEST_F(E2eDir, LasAndGridRowsGiveByteEqualPlysWithinTheirKind) {
  BenchOptions o;
  o.table = "e2e";
  o.sizes = {"2K"};
  o.runs = 1;
  o.backends = {"cgal", "gpu"};
  o.formats = {"las", "asc", "tif"};
  o.binary = CDTGPU_BINARY;
  o.first_run = false;
  o.json_path = path("e2e.json");
  ASSERT_EQ(run_e2e(o), 0);
  const nlohmann::json formats = read_json(o.json_path)["rows"][0]["formats"];
  ASSERT_EQ(formats.size(), 3u);
  EXPECT_EQ(formats[0]["points"], 2000);
  EXPECT_EQ(formats[1]["points"], 44 * 44);  // cells of 224 m
  EXPECT_EQ(formats[2]["points"], 44 * 44);
  for (const auto& format : formats)
    for (const auto& cell : format["backends"]) {
      SCOPED_TRACE(format["format"].get<std::string>() + " " + cell["backend"].get<std::string>());
      EXPECT_TRUE(cell["bytes_equal"].get<bool>());
      EXPECT_EQ(cell["counts"]["constraints"], 500);
    }
}

// The whole table on a small row with cdtgpu as the child: both backends, both formats, byte-equal PLYs,
// every stage in the JSON; about 5 s on 2 cores with lavapipe (the first run with empty caches is skipped: it
// compiles every pipeline, a minute on lavapipe).
TEST_F(E2eDir, SmallRowGivesByteEqualPlysFromBothBackendsAndFormats) {
  BenchOptions o;
  o.table = "e2e";
  o.sizes = {"2K"};
  o.runs = 1;
  o.backends = {"cgal", "gpu"};
  o.binary = CDTGPU_BINARY;
  o.first_run = false;
  o.keep_dir = path("keep");
  o.json_path = path("e2e.json");
  ASSERT_EQ(run_e2e(o), 0);

  const nlohmann::json j = read_json(o.json_path);
  EXPECT_EQ(j["tool"], "cdtgpu bench --table e2e");
  EXPECT_TRUE(j["machine"].contains("cpu"));
  ASSERT_EQ(j["rows"].size(), 1u);
  const nlohmann::json& row = j["rows"][0];
  EXPECT_EQ(row["points"], 2000);
  EXPECT_EQ(row["segments"], 500);
  ASSERT_EQ(row["formats"].size(), 2u);
  for (const auto& format : row["formats"]) {
    EXPECT_GT(format["input_bytes"].get<uint64_t>(), 0u);
    ASSERT_EQ(format["backends"].size(), 2u);
    for (const auto& cell : format["backends"]) {
      SCOPED_TRACE(format["format"].get<std::string>() + " " + cell["backend"].get<std::string>());
      EXPECT_TRUE(cell["ok"].get<bool>());
      EXPECT_TRUE(cell["bytes_equal"].get<bool>());
      EXPECT_GT(cell["wall_median_ms"].get<double>(), 0);
      EXPECT_EQ(cell["runs"].size(), 1u);
      for (const char* stage : {"read", "project", "prepare", "triangulate", "write"})
        EXPECT_TRUE(cell["stage_median_ms"].contains(stage)) << stage;
      EXPECT_EQ(cell.contains("gpu_median_ms"), cell["backend"] == "gpu");
      EXPECT_FALSE(cell.contains("first_run"));
      EXPECT_EQ(cell["counts"]["input_points"], 2000 + 500 + row["lines"].get<int>());
      EXPECT_EQ(cell["counts"]["constraints"], 500);
      EXPECT_EQ(cell["counts"]["steiner_points"], 0);
    }
  }
  // --keep leaves every output; the gpu's and cgal's PLYs of the shapefiles are the same bytes as text's
  // cgal.
  const fs::path text_cgal = dir_ / "keep" / "2000" / "text" / "out-text-cgal.ply";
  const fs::path shp_gpu = dir_ / "keep" / "2000" / "shp" / "out-shp-gpu.ply";
  ASSERT_TRUE(fs::exists(text_cgal));
  ASSERT_TRUE(fs::exists(shp_gpu));
  EXPECT_EQ(fs::file_size(text_cgal), fs::file_size(shp_gpu));
}

TEST_F(E2eDir, ABackendTheChildRejectsFailsItsRowAndTheOthersStillRun) {
  BenchOptions o;
  o.table = "e2e";
  o.sizes = {"300"};
  o.runs = 1;
  o.backends = {"no-such-backend", "cgal"};
  o.formats = {"text"};
  o.binary = CDTGPU_BINARY;
  o.json_path = path("e2e.json");
  EXPECT_EQ(run_e2e(o), 1);
  const nlohmann::json cells = read_json(o.json_path)["rows"][0]["formats"][0]["backends"];
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_FALSE(cells[0]["ok"].get<bool>());
  EXPECT_EQ(cells[0]["exit_code"], 2);  // cdtgpu's usage error
  EXPECT_TRUE(cells[1]["ok"].get<bool>());
  EXPECT_TRUE(cells[1]["bytes_equal"].get<bool>());
  EXPECT_TRUE(cells[1].contains("first_run"));  // cgal's first run: no pipelines to compile
}

// A bad --cgal-max is a usage message and exit 2, not an uncaught exception (it was "terminate called").
TEST(BenchOptions, ABadCgalMaxIsAUsageError) {
  const std::string err = testing::TempDir() + "/bench_cgal_max.txt";
  const int status = std::system((std::string(CDTGPU_BINARY) + " bench --table tiles --cgal-max 2x 2>" + err).c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream in(err);
  const std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(message.find("--cgal-max: unknown suffix in '2x'"), std::string::npos) << message;
}
