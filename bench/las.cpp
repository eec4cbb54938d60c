// cdtgpu bench --table las (see las.hpp).
#include "bench/las.hpp"

#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "bench/figures.hpp"
#include "core/error.hpp"
#include "core/workloads.hpp"
#include "io/atomic_file.hpp"
#include "io/read_las.hpp"
#include "tests/las_writer.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;
using figures::Clock;
using figures::fmt;
using figures::median;
using figures::ms_since;
using json = nlohmann::ordered_json;

std::string make_dir(const BenchOptions& o) {
  if (!o.keep_dir.empty()) {
    fs::create_directories(o.keep_dir);
    return fs::absolute(o.keep_dir).string();
  }
  std::string tmpl = (fs::temp_directory_path() / "cdtgpu-las-XXXXXX").string();
  if (!mkdtemp(tmpl.data())) throw std::runtime_error("cannot create a temporary folder");
  return tmpl;
}

// The workload as a LAS file: millimetres from the workload's corner, every other point class 2.
std::string write_las(const InputSet& w, int format, const std::string& path) {
  test::LasFile f;
  f.format = format;
  f.minor = format >= 6 ? 4 : 2;
  f.scale[0] = f.scale[1] = f.scale[2] = 0.001;
  f.offset[0] = 500000, f.offset[1] = 6000000, f.offset[2] = 0;
  f.points.resize(w.points.size());
  for (size_t i = 0; i < w.points.size(); ++i) {
    const Point3& p = w.points[i];
    f.points[i] = {.X = int32_t(std::llround((p.x - 500000) * 1000)),
                   .Y = int32_t(std::llround((p.y - 6000000) * 1000)),
                   .Z = int32_t(std::llround(p.z * 1000)),
                   .cls = uint8_t(i % 2 ? 2 : 1)};
  }
  std::ofstream(path, std::ios::binary) << test::las_bytes(f);
  return path;
}

}  // namespace

int run_las(const BenchOptions& o) {
  std::vector<uint64_t> sizes;
  for (const std::string& s : o.sizes) sizes.push_back(parse_bench_size(s));
  if (sizes.empty()) sizes = o.quick ? std::vector<uint64_t>{1000000} : std::vector<uint64_t>{10000000, 50000000};
  const std::string dir = make_dir(o);
  std::printf("LAS reading (io/read_las), in process, file in the page cache; median of %d runs; %u threads\n"
              "CPU: %s\n\n", o.runs, std::thread::hardware_concurrency(), bench_cpu_model().c_str());
  std::printf("%12s %7s %9s %8s %10s %8s %10s\n", "points", "format", "file MB", "keep", "read ms", "GB/s",
              "Mpoints/s");
  json rows = json::array();
  int status = 0;
  for (const uint64_t n : sizes) {
    const InputSet w = uniform_points(n, o.seed);
    for (const int format : {1, 6}) {
      const std::string path = write_las(w, format, (fs::path(dir) / ("points_f" + std::to_string(format) + ".las")).string());
      const double record_bytes = double(n) * test::las_format_size(format);
      for (const bool ground : {false, true}) {
        LasFilter filter;
        if (ground) {
          filter.classes.reset();
          filter.classes.set(2);
        }
        std::vector<double> ms;
        for (int r = 0; r <= o.runs; ++r) {  // run 0: the warm-up
          InputSet in;
          const auto t0 = Clock::now();
          read_las(path, filter, in);
          if (r) ms.push_back(ms_since(t0));
          if (r == 0) {  // what was written reads back: the count, and every point within a micrometre
            double worst = 0;
            for (size_t i = 0, k = ground ? 1 : 0; i < in.points.size() && k < n; ++i, k += ground ? 2 : 1)
              worst = std::max({worst, std::abs(in.points[i].x - w.points[k].x),
                                std::abs(in.points[i].y - w.points[k].y), std::abs(in.points[i].z - w.points[k].z)});
            if (in.points.size() != (ground ? n / 2 : n) || worst > 1e-6) {
              std::fprintf(stderr, "%s: %zu points read (expected %llu), largest difference %g\n", path.c_str(),
                           in.points.size(), static_cast<unsigned long long>(ground ? n / 2 : n), worst);
              status = 1;
            }
          }
        }
        const double med = median(ms);
        std::printf("%12llu %7d %9.0f %8s %10s %8s %10s\n", static_cast<unsigned long long>(n), format,
                    double(fs::file_size(path)) / 1e6, ground ? "class 2" : "all", fmt(med).c_str(),
                    fmt(record_bytes / med / 1e6, 2).c_str(), fmt(double(n) / med / 1e3).c_str());
        rows.push_back({{"points", n}, {"format", format}, {"file_bytes", fs::file_size(path)},
                        {"keep", ground ? "class 2" : "all"}, {"read_ms", ms}, {"median_ms", med},
                        {"gb_per_s", record_bytes / med / 1e6}});
      }
      if (o.keep_dir.empty()) fs::remove(path);
    }
  }
  if (o.keep_dir.empty()) fs::remove_all(dir);
  else std::printf("\nfiles kept in %s\n", dir.c_str());
  if (!o.json_path.empty()) {
    json j = {{"table", "las"}, {"cpu", bench_cpu_model()}, {"threads", std::thread::hardware_concurrency()},
              {"date", bench_utc_now()}, {"rows", rows}};
    write_file_atomically(o.json_path, [&](std::ostream& out) { out << j.dump(2) << '\n'; });
  }
  return status;
}

}  // namespace cdtgpu
