#include "cli/gpu_start.hpp"

#include <cctype>
#include <chrono>
#include <cstdlib>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <spdlog/spdlog.h>

#include "gpu/buffers.hpp"
#include "gpu/tile_triangulator.hpp"
#include "core/error.hpp"
#include "core/timing.hpp"
#include "io/geotiff.hpp"
#include "io/mapped_files.hpp"
#include "io/read_las.hpp"

namespace cdtgpu {

uint64_t auto_min_points() {
  if (const char* v = std::getenv("CDTGPU_AUTO_MIN_POINTS"); v && *v) return std::strtoull(v, nullptr, 10);
  const uint64_t cores = std::clamp(std::thread::hardware_concurrency(), 1u, kAutoMaxCores);
  return std::max(kAutoMinPoints, kAutoPointsPerCore * cores);
}

uint64_t batch_auto_min_points() {
  if (const char* v = std::getenv("CDTGPU_AUTO_MIN_POINTS"); v && *v) return std::strtoull(v, nullptr, 10);
  return kBatchAutoMinPoints;
}

namespace {

// Points in a text file, from its size and the first 64 KiB: lines for XYZ, coordinates (commas and line ends)
// for WKT. An ASCII grid says its size in its header (ncols x nrows); a shapefile point record is 28 bytes or
// more, so size / 28 bounds it; GeoTIFF and LAS headers say their cells and points.
uint64_t estimate_points(const std::string& path, uint64_t size, const std::string& ext) {
  if (ext == ".shp") return size / 28;
  if (ext == ".tif" || ext == ".tiff") return geotiff_cell_count(path);
  if (ext == ".las") {  // the header's count (before the class and return filters)
    try {
      const files::Open f(files::open(path));
      if (f) return parse_las_header(f->bytes(), path).point_count;
    } catch (const InputError&) {
    }
    return size / 20;  // the shortest record
  }
  std::ifstream in(path, std::ios::binary);
  std::string head(64 << 10, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(size_t(in.gcount()));
  if (head.empty()) return 0;
  if (ext == ".asc") {
    std::istringstream h(head);
    uint64_t ncols = 0, nrows = 0;
    for (std::string key, value; h >> key >> value;) {
      for (char& c : key) c = char(std::tolower(static_cast<unsigned char>(c)));
      if (key == "ncols") ncols = std::strtoull(value.c_str(), nullptr, 10);
      if (key == "nrows") nrows = std::strtoull(value.c_str(), nullptr, 10);
      if (ncols && nrows) return ncols * nrows;
    }
    return size / 2;
  }
  const uint64_t marks = uint64_t(std::count(head.begin(), head.end(), '\n')) +
                         (ext == ".wkt" ? uint64_t(std::count(head.begin(), head.end(), ',')) : 0);
  return marks ? size / std::max<uint64_t>(1, head.size() / marks) : 1;
}

}  // namespace

uint64_t estimate_input_points(const std::vector<std::string>& paths) {
  uint64_t total = 0;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (p == "-" || !std::filesystem::is_regular_file(p, ec)) continue;
    std::string ext = std::filesystem::path(p).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    total += estimate_points(p, std::filesystem::file_size(p, ec), ext);
  }
  return total;
}

namespace {
constexpr uint64_t kDevicePoolFrom = 32'000'000;
}  // namespace

GpuStart::GpuStart(const std::string& device, bool hardware_only, uint64_t expected_points, bool device_pool,
                   bool tiled, int nth_gpu, int processes_on_host) {
  pending_ = std::async(std::launch::async, [=, this] {
    auto r = std::make_unique<Ready>();
    gpu::ContextOptions options;
    options.device = device;
    options.nth_gpu = nth_gpu;
    options.processes_on_host = processes_on_host;
    options.hardware_only = hardware_only;
    // The download of ~2n triangles of 12 bytes is the largest copy; an eighth more for the estimate's error.
    // For any input the device may take in one piece: grown by the copies instead, it was pinned twice more
    // on the run's path (2 then 3 GB at 100M points, 1.5 s on the H200 machine), where now it is pinned beside
    // the reading. Tiled inputs bring their own (gpu/tile_triangulator), for their merge too: the 1 GiB pinned
    // here for it made the tile devices open ~0.4 s later (100M points in tiles of 20M on the 2 x H200 host),
    // and their staging and memory pools then ended after prepare. Tiles of --max-tile-points made these for a
    // piece that never came: 3 GB of staging and 32 GB of device memory at 100M points in tiles of 20M, which
    // the tiles then waited for (0.7-1.1 s, session 57).
    const bool one_piece = !tiled && expected_points <= gpu::max_tile_points_of_any_device();
    options.staging_bytes = one_piece ? expected_points * 27 : 0;
    // And the device memory of its buffers, where their allocation between the stages costs more than the
    // reading takes to hide it (~30 ms a GB on the H200 machine): the run's peak, ~260 bytes a point at 10^8.
    if (device_pool && one_piece && expected_points >= kDevicePoolFrom)
      options.device_pool_bytes = expected_points * 260;
    options.staging_ms = &staging_ms;
    auto t = std::chrono::steady_clock::now();
    r->ctx = gpu::create_context(options);
    context_ms = ms_since(t);
    t = std::chrono::steady_clock::now();
    r->cdt = std::make_unique<gpu::GpuCdt>(r->ctx);  // queues every pipeline's compile
    pipelines_ms = ms_since(t);
    return r;
  });
}

GpuStart::~GpuStart() {
  if (closing_.joinable()) closing_.join();  // it joins closing_later_ first
  if (closing_later_.joinable()) closing_later_.join();
  if (pending_.valid()) pending_.wait();
  drop_ahead();
  if (ready_) ready_->cdt.reset();  // its passes before the context
}

bool GpuStart::begin_ahead(std::function<std::shared_ptr<void>(gpu::GpuCdt&)> work) {
  if (ahead_.valid()) return false;
  {
    std::lock_guard<std::mutex> lock(settle_mutex_);
    if (failed_) return false;
  }
  // The start waited for on the work's thread: prepare does not wait for it (under MPI two processes making
  // their devices at once took 0.4-0.55 s each, and prepare waited ~0.6 s for it).
  ahead_ = std::async(std::launch::async, [this, work = std::move(work)]() -> std::shared_ptr<void> {
    settle();
    if (!ready_) return nullptr;  // the start failed: cdt() says why
    return work(*ready_->cdt);
  });
  return true;
}

std::shared_ptr<void> GpuStart::take_ahead() {
  if (!ahead_.valid()) return nullptr;
  try {
    return ahead_.get();
  } catch (const std::exception& e) {
    spdlog::debug("gpu start: the work begun ahead failed ({}): done again now", e.what());
    return nullptr;
  }
}

void GpuStart::drop_ahead() {
  if (ahead_.valid()) take_ahead().reset();
}

// The start's outcome, once: the device ready, or its failure kept for cdt() to rethrow.
void GpuStart::settle() {
  std::lock_guard<std::mutex> lock(settle_mutex_);
  if (ready_ || failed_ || !pending_.valid()) return;
  try {
    ready_ = pending_.get();
  } catch (...) {
    failed_ = std::current_exception();
  }
}

void GpuStart::close_in_background() {
  if (closing_.joinable()) return;
  closing_ = std::thread([this] {
    if (closing_later_.joinable()) closing_later_.join();  // it may free staging on this device
    drop_ahead();
    settle();  // a start that failed has nothing to close
    if (!ready_) return;
    const auto t0 = std::chrono::steady_clock::now();
    // Closed, not left to the exit, although the close (buffers 8, staging 6, device 35, instance 13 ms on the
    // H200 machine) outlasts a 2M run's write: left to the exit, the device made the run 25-30 ms slower, the
    // instance alone 6-14 ms (session 56, docs/performance.md).
    ready_->cdt.reset();  // its passes before the context
    spdlog::debug("gpu close: buffers and passes: {:.1f} ms", ms_since(t0));
    ready_.reset();  // the context saves its pipeline cache as it goes
  });
}

void GpuStart::close_later(std::function<void()> close) {
  if (closing_later_.joinable()) closing_later_.join();
  closing_later_ = std::thread(std::move(close));
}

void GpuStart::leave_for_exit() {
  if (closing_.joinable()) {
    closing_.join();
    return;
  }
  if (closing_later_.joinable()) closing_later_.join();
  drop_ahead();
  settle();  // a start that failed has nothing to leave
  if (!ready_) return;
  gpu::store_pipeline_cache(ready_->ctx);
  (void)ready_.release();  // deliberately never destroyed
}

gpu::GpuCdt& GpuStart::cdt() {
  settle();
  if (failed_) std::rethrow_exception(failed_);
  return *ready_->cdt;
}

const gpu::Context& GpuStart::context() {
  cdt();
  return ready_->ctx;
}

GpuStart& GpuStarts::start(const std::string& device, bool hardware_only, uint64_t expected_points, bool tiled,
                           unsigned copy) {
  std::lock_guard lock(mutex_);
  std::unique_ptr<GpuStart>& s = starts_[{device, hardware_only, copy}];
  if (!s)
    s = std::make_unique<GpuStart>(device, hardware_only, expected_points, device_pool, tiled, nth_gpu,
                                   processes_on_host);
  return *s;
}

void GpuStarts::leave_for_exit() {
  std::lock_guard lock(mutex_);
  for (auto& [key, s] : starts_) s->leave_for_exit();
}

void GpuStarts::close_in_background() {
  std::lock_guard lock(mutex_);
  for (auto& [key, s] : starts_) s->close_in_background();
}

}  // namespace cdtgpu
