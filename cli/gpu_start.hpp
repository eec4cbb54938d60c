// The GPU backend made ready on a thread of its own (Vulkan instance, device, pipelines) while the inputs are
// read, and the `--backend auto` rule that decides whether a run uses it.
#pragma once
#include <cstdint>
#include <exception>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "gpu/cdt_pipeline.hpp"
#include "gpu/context.hpp"

namespace cdtgpu {

// Below auto_min_points() input points `--backend auto` runs the CPU (CGAL, in tiles on every core) without
// touching Vulkan: the GPU's start-up (instance, device, pipelines from the cache, ~0.2 s) costs more than the
// CPU's whole triangulation. That grows with the points a core: kAutoPointsPerCore a core (at most
// kAutoMaxCores cores counted), never below kAutoMinPoints. Measured with `cdtgpu bench --table e2e` on the
// H200 machine's 16 cores (docs/performance.md, 2026-11-29): 500K + 125K points 208 ms on the CPU against 284
// on the GPU, 1M + 250K 355 against 316; kAutoMinPoints from one core's CGAL (the H100 machine, 2026-11-25).
// CDTGPU_AUTO_MIN_POINTS overrides it.
constexpr uint64_t kAutoMinPoints = 100000;
constexpr uint64_t kAutoPointsPerCore = 45000;
constexpr unsigned kAutoMaxCores = 32;
uint64_t auto_min_points();
// In a batch of kBatchWarmJobs jobs or more the start-up is paid once, and auto sends jobs of this many points
// to the GPU: 200 jobs of 20K points + 5K segments on the H100 machine took 16.5 ms a job on the GPU, 42-59 on
// CGAL (docs/performance.md). CDTGPU_AUTO_MIN_POINTS, when set, rules batches too.
constexpr uint64_t kBatchAutoMinPoints = 10000;
constexpr size_t kBatchWarmJobs = 8;
uint64_t batch_auto_min_points();

// About how many points the input files hold, from their sizes and first bytes (stdin counts 0). Auto starts
// the GPU while reading when this reaches auto_min_points(): a guess that decides what overlaps, never what
// runs (that is decided from the points read). A wrong guess costs a start that is waited for at exit.
uint64_t estimate_input_points(const std::vector<std::string>& paths);

class GpuStart {
 public:
  // Starts creating the context and every pipeline now. hardware_only: refuse a CPU Vulkan driver.
  // expected_points (the estimate of the input): the start also allocates the staging memory that the
  // triangulation's upload and download will need, ~24 bytes a point, off the critical path.
  // device_pool: device memory for a large one-piece run made ahead too (gpu/device_memory_pool.hpp). tiled: the
  // run is tiled whatever the devices take (--max-tile-points): neither (its tiles and merge bring their own).
  // nth_gpu, processes_on_host: an MPI rank's own GPU (gpu::ContextOptions').
  GpuStart(const std::string& device, bool hardware_only, uint64_t expected_points = 0, bool device_pool = false,
           bool tiled = false, int nth_gpu = -1, int processes_on_host = 1);
  ~GpuStart();
  // Waits for the start; rethrows its DeviceError (on every call: a failed start is not tried again).
  gpu::GpuCdt& cdt();
  const gpu::Context& context();
  // For a process about to exit: saves the pipeline cache and leaves the device, its buffers and pipelines to
  // the operating system. Tearing them down took ~75 ms on the H100 machine, as long as a 2M-point CDT.
  void leave_for_exit();
  // For a process whose device work is done: saves the pipeline cache and tears the device down on a thread of
  // its own, beside the writing of the outputs; leave_for_exit then waits for it. No call to cdt() or
  // context() may follow. Left to the operating system, the teardown made the exit of a 2M-point run 45 ms
  // longer on the H100 machine (65 ms against 20 for the CGAL backend).
  void close_in_background();
  // Device objects a run is done with (a tiled run's other devices, the tiles' staging): `close` destroys them on
  // a thread of its own, beside the outputs' writing; leave_for_exit and the destructor wait for it. At 1B
  // points their buffers took ~1.2 s a device and 0.2 s a 3 GB staging slot to free, one after another, before
  // the writing began. One at a time: a second waits for the first.
  void close_later(std::function<void()> close);
  // Work on the started device begun while the input is prepared (a tiled run's devices and their staging:
  // cli/stages.cpp, open_tiles_early): on a thread of its own, once the start is done; false (nothing run) if the
  // start failed already or work was begun already (a start that fails later runs nothing). take_ahead waits for its result (null if none,
  // or if it failed: logged); a result not taken is destroyed before the device closes.
  bool begin_ahead(std::function<std::shared_ptr<void>(gpu::GpuCdt&)> work);
  std::shared_ptr<void> take_ahead();
  // Host milliseconds of the start's parts: instance and device, queueing every pipeline, staging memory.
  double context_ms = 0, pipelines_ms = 0, staging_ms = 0;

 private:
  struct Ready {
    gpu::Context ctx;
    std::unique_ptr<gpu::GpuCdt> cdt;
  };
  void settle();  // thread-safe: the work begun ahead waits for the start on its own thread
  void drop_ahead();
  std::mutex settle_mutex_;
  std::future<std::unique_ptr<Ready>> pending_;
  std::unique_ptr<Ready> ready_;
  std::future<std::shared_ptr<void>> ahead_;
  std::exception_ptr failed_;
  std::thread closing_;
  std::thread closing_later_;  // close_later's
};

// The GPU starts of one process, one per (device, hardware_only), each made when first asked for and kept for
// every later job: a batch pays for one Vulkan device and its pipelines. Thread-safe.
class GpuStarts {
 public:
  // The fewest input points for which `--backend auto` uses the GPU in this process: auto_min_points(), or
  // batch_auto_min_points() for a batch of many jobs.
  uint64_t auto_min_points = cdtgpu::auto_min_points();
  // Whether a start for a large one-piece input makes its device memory ahead: not where another MPI rank may
  // take the same GPU (TriangulateOptions::devices_shared).
  bool device_pool = true;
  // An MPI rank's own GPU, for starts whose device is "" (TriangulateOptions::rank_gpu, host_ranks).
  int nth_gpu = -1;
  int processes_on_host = 1;
  // The start for this device and rule: started now with `expected_points` (and `tiled`, GpuStart's), or the one
  // started before. `copy`: another start on the same device (a batch's second worker there, cli/batch_devices).
  GpuStart& start(const std::string& device, bool hardware_only, uint64_t expected_points, bool tiled = false,
                  unsigned copy = 0);
  // GpuStart::leave_for_exit for each.
  void leave_for_exit();
  // GpuStart::close_in_background for each.
  void close_in_background();

 private:
  std::mutex mutex_;
  std::map<std::tuple<std::string, bool, unsigned>, std::unique_ptr<GpuStart>> starts_;
};

}  // namespace cdtgpu
