#include "cli/batch.hpp"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <semaphore>
#include <set>
#include <thread>

#include <spdlog/spdlog.h>

#include "cli/batch_devices.hpp"
#include "cli/job_file.hpp"
#include "cli/job_log.hpp"
#include "cli/memory.hpp"
#include "cli/progress.hpp"
#include "cli/stages.hpp"
#include "core/error.hpp"
#include "core/timing.hpp"
#include "gpu/check.hpp"

namespace cdtgpu {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Jobs held at once: one being read, and a device worker's and a writer's for each worker.
constexpr std::ptrdiff_t kReading = 1, kPerWorker = 2;

struct BatchJob {
  size_t index = 0;  // in file order
  uint64_t memory = 0;  // what it holds of the MemoryGate
  JobLine line;
  std::string label;  // "line N"
  Job job;
  int exit_code = 0;  // the single run's: 2 bad input or usage, 3 device or other failure
  Clock::time_point t0;
};

// A queue between two stage threads; a null job says the stream ended.
class JobQueue {
 public:
  void push(std::unique_ptr<BatchJob> j) {
    {
      std::lock_guard lock(mutex_);
      jobs_.push_back(std::move(j));
    }
    cv_.notify_one();
  }
  std::unique_ptr<BatchJob> pop() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return !jobs_.empty(); });
    std::unique_ptr<BatchJob> j = std::move(jobs_.front());
    jobs_.pop_front();
    return j;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<BatchJob>> jobs_;
};

// The jobs in flight kept within the machine's memory together, by their estimates (the bytes a point that a
// single run is checked by, cli/memory.hpp): a job is read once the jobs before it leave it room, or when it is
// alone (one too large for the machine is refused by its own check). Three jobs of 40 % of the memory each would
// otherwise be read at once and killed by the kernel.
class MemoryGate {
 public:
  explicit MemoryGate(uint64_t budget) : budget_(budget) {}
  // Waits for room for `bytes` (none: budget 0, the memory unknown); returns what it holds, for leave().
  uint64_t enter(uint64_t bytes, const std::string& label) {
    if (!budget_) return 0;
    bytes = std::min(bytes, budget_);
    std::unique_lock lock(mutex_);
    if (used_ && used_ + bytes > budget_)
      spdlog::debug("{}: waits for memory: about {} MB, {} MB held by the jobs before it, {} MB in all", label,
                    bytes >> 20, used_ >> 20, budget_ >> 20);
    cv_.wait(lock, [&] { return used_ == 0 || used_ + bytes <= budget_; });
    used_ += bytes;
    return bytes;
  }
  void leave(uint64_t bytes) {
    {
      std::lock_guard lock(mutex_);
      used_ -= bytes;
    }
    cv_.notify_all();
  }

 private:
  const uint64_t budget_;
  std::mutex mutex_;
  std::condition_variable cv_;
  uint64_t used_ = 0;
};

// Runs one stage of a job that has not failed; a failure is logged with the job's line and kept as its exit code
// (the codes of a single run).
void stage(BatchJob& b, const std::function<void()>& f) {
  if (b.exit_code) return;
  JobLogScope scope(b.label);
  try {
    f();
    return;
  } catch (const InputError& e) {
    spdlog::error("{}", e.what());
    b.exit_code = 2;
  } catch (const UsageError& e) {
    spdlog::error("{}", e.what());
    b.exit_code = 2;
  } catch (const gpu::DeviceError& e) {
    spdlog::error("{}", e.what());
    spdlog::error("--backend cgal computes the same triangulation on the CPU, without a GPU");
    b.exit_code = 3;
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory");
    b.exit_code = 3;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    b.exit_code = 3;
  }
}

// A path as the batch compares it: absolute, normalised, links resolved where they exist.
std::string same_file_key(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal().string() : p.string();
}

// Which job last writes each file, and how many jobs are written: a job reading a file that a job still in
// flight writes waits until that one is done (and every job before it: jobs are written in any order).
class Written {
 public:
  void will_write(size_t index, const std::vector<std::string>& outputs) {
    std::lock_guard lock(mutex_);
    for (const std::string& o : outputs)
      if (o != "-") writer_[same_file_key(o)] = index;
  }
  void wait_for_writers_of(const std::vector<std::string>& inputs) {
    std::unique_lock lock(mutex_);
    for (const std::string& in : inputs) {
      auto it = writer_.find(same_file_key(in));
      if (it == writer_.end()) continue;
      const size_t writer = it->second;
      cv_.wait(lock, [&] { return all_before_ > writer; });
    }
  }
  void done(size_t index) {
    {
      std::lock_guard lock(mutex_);
      ++count_;
      later_.insert(index);
      while (later_.erase(all_before_)) ++all_before_;
    }
    cv_.notify_all();
  }
  size_t count() {
    std::lock_guard lock(mutex_);
    return count_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::map<std::string, size_t> writer_;
  size_t count_ = 0, all_before_ = 0;  // jobs written; every job below all_before_ written
  std::set<size_t> later_;             // written, above a job not yet written
};

// A lock a GPU start, held through a job's device stages: a worker's own start is its alone, but a job that
// names its own --device takes that device's start, which a worker may be using.
class DeviceLocks {
 public:
  std::mutex& of(const GpuStart* start) {
    std::lock_guard lock(mutex_);
    return locks_[start];
  }

 private:
  std::mutex mutex_;
  std::map<const GpuStart*, std::mutex> locks_;
};

}  // namespace

int run_batch(const BatchOptions& options) {
  const std::vector<JobLine> lines = read_job_file(options.jobs);
  if (!options.stats_dir.empty()) {
    std::error_code ec;
    fs::create_directories(options.stats_dir, ec);
    if (!fs::is_directory(options.stats_dir))
      throw UsageError("--stats-dir " + options.stats_dir + ": cannot create the folder");
  }
  // The device workers (cli/batch_devices), as --devices names them (a bad index is an error before any thread
  // starts); without it one, on the single run's device. Each has a writer.
  const std::vector<DeviceWorker> workers =
      options.devices.empty() ? std::vector<DeviceWorker>{} : batch_device_workers(options.devices, options.defaults.device);
  const size_t worker_count = std::max<size_t>(1, workers.size());
  if (worker_count > 1) {
    std::string names;
    for (size_t k = 0; k < workers.size(); ++k)
      names += (k ? ", " : "") + std::to_string(k + 1) + " on " + workers[k].name;
    spdlog::info("batch: {} device workers: {}", workers.size(), names);
  }
  GpuStarts gpus;  // a device a worker
  if (lines.size() >= kBatchWarmJobs) gpus.auto_min_points = batch_auto_min_points();
  JobQueue to_device, to_writer;
  std::counting_semaphore<1024> slots(kReading + kPerWorker * std::ptrdiff_t(worker_count));
  const HostMemory machine = host_memory();
  MemoryGate memory(machine.available ? machine.available : machine.total);
  Written written;
  std::mutex summary_mutex;
  std::vector<int> failed_lines;

  Progress progress([&] {
    const size_t done = written.count();
    std::lock_guard lock(summary_mutex);
    return "batch: " + std::to_string(done) + " of " + std::to_string(lines.size()) + " jobs done" +
           (failed_lines.empty() ? "" : " (" + std::to_string(failed_lines.size()) + " failed)");
  });

  // Writing: the outputs, the stats, the job's summary line.
  auto write_job = [&](std::unique_ptr<BatchJob> b) {
    Job& job = b->job;
    stage(*b, [&] {
      write_outputs(job);
      count_results(job);
    });
    stage(*b, [&] { release_job(job); });
    stage(*b, [&] { write_job_stats(job); });
    const double ms = ms_since(b->t0);
    {
      std::lock_guard lock(summary_mutex);
      if (b->exit_code) failed_lines.push_back(b->line.number);
    }
    if (b->exit_code)
      spdlog::error("{}: failed (exit code {}), {:.0f} ms", b->label, b->exit_code, ms);
    else
      spdlog::info("{}: ok, {:.0f} ms, {} triangles", b->label, ms, job.stats.counts["triangles"].dump());
    const size_t index = b->index;
    const uint64_t held = b->memory;
    b.reset();
    memory.leave(held);
    written.done(index);
    slots.release();
  };
  // As many writers as workers: a job's PLY is packed and written on one thread (10M points: 0.3-0.4 s, longer
  // than its device stages).
  auto writing = [&] {
    while (std::unique_ptr<BatchJob> b = to_writer.pop()) write_job(std::move(b));
  };
  std::vector<std::thread> writers;
  for (size_t k = 0; k < worker_count; ++k) writers.emplace_back(writing);

  DeviceLocks locks;
  // A worker's device stages, one job at a time: the job's GPU start moved to the worker's device, unless it
  // names a device of its own.
  auto device_stage = [&](size_t k) {
    while (std::unique_ptr<BatchJob> b = to_device.pop()) {
      Job& job = b->job;
      stage(*b, [&] {
        if (job.start && k < workers.size() && job.options.device == options.defaults.device) {
          job.start = &gpu_start_on(job, gpus, workers[k].device, workers[k].copy);
          if (workers.size() > 1) spdlog::debug("device stages on worker {} of {}", k + 1, workers.size());
        }
        std::unique_lock<std::mutex> device;
        if (job.start) device = std::unique_lock(locks.of(job.start));
        triangulate_job(job);
        apply_job_regions(job);
        derive_outputs(job);
      });
      if (b->exit_code) {  // a failed job's device objects go now, on the device's thread
        job.gpu_raster.reset();
        job.gpu_contours.reset();
      }
      to_writer.push(std::move(b));
    }
  };
  std::vector<std::thread> more_workers;  // the first runs on this thread, once the reader has begun
  for (size_t k = 1; k < worker_count; ++k) more_workers.emplace_back(device_stage, k);

  // Reading: the line's options, the output checks, the inputs read and prepared.
  std::thread reader([&] {
    for (size_t i = 0; i < lines.size(); ++i) {
      slots.acquire();
      auto b = std::make_unique<BatchJob>();
      b->index = i;
      b->line = lines[i];
      b->label = "line " + std::to_string(b->line.number);
      b->t0 = Clock::now();
      Job& job = b->job;
      stage(*b, [&] {
        if (!b->line.error.empty()) throw UsageError(b->line.error);
        job.options = parse_job_words(b->line.words, options.defaults);
        job.stage_progress = false;
        job.keep_device_buffers = true;
        if (!options.stats_dir.empty())
          job.stats_copy = (fs::path(options.stats_dir) / (std::to_string(b->line.number) + ".json")).string();
        if (options.jobs == "-")
          for (const std::string& in : job.options.input.inputs)
            if (in == "-") throw UsageError("stdin holds the job list: a job cannot read WKT from it");
        check_job(job);
        written.wait_for_writers_of(job.input_paths);
        written.will_write(i, job.outputs);
        start_gpu_early(job, gpus);
        b->memory = memory.enter(estimated_peak_bytes(job), b->label);
        read_job(job);
        choose_backend(job, gpus);
        prepare_job(job);
        resolve_early(job);
      });
      to_device.push(std::move(b));
    }
    for (size_t k = 0; k < worker_count; ++k) to_device.push(nullptr);  // one a worker
  });

  device_stage(0);
  reader.join();
  for (std::thread& w : more_workers) w.join();
  for (size_t k = 0; k < worker_count; ++k) to_writer.push(nullptr);  // one a writer
  gpus.close_in_background();  // beside the last jobs' writing: the reader is done with the devices too
  for (std::thread& w : writers) w.join();
  progress.stop();
  gpus.leave_for_exit();

  if (failed_lines.empty()) {
    spdlog::info("batch: {} jobs, all ok", lines.size());
    return 0;
  }
  std::sort(failed_lines.begin(), failed_lines.end());  // written in any order
  std::string which;
  for (int n : failed_lines) which += (which.empty() ? "" : ", ") + std::to_string(n);
  spdlog::error("batch: {} of {} jobs failed (line{} {})", failed_lines.size(), lines.size(),
                failed_lines.size() > 1 ? "s" : "", which);
  return kSomeJobsFailed;
}

}  // namespace cdtgpu
