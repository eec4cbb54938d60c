#include "gpu/tile_triangulator.hpp"

#include <tbb/task_arena.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

#include "core/timing.hpp"
#include "gpu/check.hpp"
#include "gpu/clock_hold.hpp"
#include "gpu/device_memory_pool.hpp"
#include "gpu/device_pool.hpp"
#include "gpu/devices.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout_dt.h"

namespace cdtgpu::gpu {

namespace {

double ms(std::chrono::steady_clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

void add(std::vector<std::pair<std::string, double>>& sum,
         const std::vector<std::pair<std::string, double>>& one) {
  for (const auto& [name, ms] : one) {
    auto it = std::find_if(sum.begin(), sum.end(), [&](const auto& x) { return x.first == name; });
    if (it == sum.end())
      sum.emplace_back(name, ms);
    else
      it->second += ms;
  }
}

}  // namespace

TileTriangulator gpu_tile_triangulator(const GpuCdt& cdt, GpuCdtStats* sum) {
  return gpu_tile_triangulator(std::vector<const GpuCdt*>{&cdt}, sum);
}

TileTriangulator gpu_tile_triangulator(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum) {
  return gpu_tiles(std::move(cdts), sum).triangulate;
}

namespace {

// Runs work(cdt, stats) on a free device: its stats added to `sum`, a DeviceError given the call's name.
class OnDevice {
 public:
  OnDevice(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum, uint64_t warm_up_from, uint64_t pools_from)
      : cdts_(std::move(cdts)), sum_(sum), warm_up_from_(warm_up_from), pools_from_(pools_from), pool_(cdts_.size()),
        slots_(kSlotsPerDevice * cdts_.size()) {
    for (size_t i = 0; i < kSlotsPerDevice * cdts_.size(); ++i) staging_.push_back(std::make_unique<HostStaging>());
    for (size_t d = 0; d < cdts_.size(); ++d) copying_.push_back(std::make_unique<std::mutex>());
    reserved_.resize(staging_.size());
    pools_made_.resize(cdts_.size());
    holding_.resize(cdts_.size());
  }

  // Every slot's staging buffer for tiles of `vertices`, each device's slots in turn on a thread of the
  // device's own: pinned memory takes ~0.3 ms per MB (1.0-1.7 s for a 3 GB slot at 1B points), which the
  // resolve and the plan hide. A tile waits only for its own slot: on two devices the first tiles waited
  // 2.3-2.9 s for all four. A device's next slot is pinned without waiting for its memory pool (a tile waits for
  // both), so that less pinning runs beside the first tiles' uploads: those take 128-244 ms against 9-10 for
  // later ones (tiles of 20M points on the 2 x H200 host, beside the pools' allocation and the other slots'
  // pinning; writing each slot once by its device when pinned did not make them faster).
  //
  // The first reserve also warms each device up (GpuCdt::warm_up_tiles) in its first slot, unless a tile has
  // begun by then: the device's buffers for tiles are made while the host resolves and plans. Asked again for
  // no more than before (the plan's own call after the CLI's), it does nothing. For tiles of pools_from points
  // or more, each device's memory pool is made beside its slots' pinning; a tile waits for it too (pools_made_).
  void reserve(uint64_t vertices) {
    if (vertices <= reserved_vertices_ || released_) return;  // released: a tile's own fit() sizes slot 0
    const bool warm = reserved_vertices_ == 0 && vertices >= warm_up_from_;  // the first reserve
    // Their clocks held up from the first reserve (after the warm-up, if any) to the first tile.
    const bool hold = reserved_vertices_ == 0 && holds_clocks();
    const bool pools = vertices >= pools_from_;
    reserved_vertices_ = vertices;
    allocating_.clear();  // joins an earlier reserve's threads
    const uint64_t bytes = GpuCdt::staging_bytes(vertices);
    const size_t devices = cdts_.size();
    filled_ = std::vector<std::promise<void>>(staging_.size());
    for (size_t slot = 0; slot < staging_.size(); ++slot) reserved_[slot] = filled_[slot].get_future().share();
    for (size_t d = 0; d < devices; ++d) {
      pools_made_[d] = {};
      if (pools)  // make_pool throws nothing
        pools_made_[d] = std::async(std::launch::async, [this, d, vertices] { make_pool(d, vertices); }).share();
      allocating_.emplace_back([this, d, devices, bytes, vertices, warm, hold] {
        if (hold && !warm && tiles_begun_.load() == 0) hold_clock(d);
        for (size_t slot = d; slot < staging_.size(); slot += devices) try {
            staging_[slot]->fit(cdts_[d]->context(), bytes);
            if (warm && slot == d) {
              if (pools_made_[d].valid()) pools_made_[d].wait();
              warm_up(d, *staging_[slot], vertices);
              if (hold && tiles_begun_.load() == 0) hold_clock(d);
            }
            filled_[slot].set_value();
          } catch (...) {
            filled_[slot].set_exception(std::current_exception());
          }
      });
    }
  }

  // Slot `slot` of device d pinned and the device's memory pool made, by reserve(); its pinning's error rethrown.
  void wait_reserved(size_t slot, size_t d) {
    if (const auto reserved = reserved_[slot]; reserved.valid()) reserved.get();
    if (const auto pool = pools_made_[d]; pool.valid()) pool.wait();
  }

  // Device d's warm-up, holding the device; a failure only logged (the tiles meet it again, with their names).
  void warm_up(size_t d, HostStaging& staging, uint64_t vertices) {
    if (tiles_begun_.load() > 0) return;
    pool_.take(d);
    const DevicePool::Held held{pool_, d};
    const std::lock_guard<std::mutex> lock(*copying_[d]);  // and its copy queue
    const auto t0 = std::chrono::steady_clock::now();
    try {
      cdts_[d]->warm_up_tiles(vertices, staging);
      warm_ups_.fetch_add(1);
      spdlog::debug("device {}: warmed up for tiles of {} points in {:.0f} ms", d, vertices, ms_since(t0));
    } catch (const std::exception& e) {
      cdts_[d]->drop_kept();
      spdlog::debug("device {}: no warm-up for tiles of {} points: {}", d, vertices, e.what());
    }
  }

  // Devices that warm up for large enough tiles (hardware GPUs, not lavapipe) have clocks worth holding up.
  bool holds_clocks() const { return warm_up_from_ != UINT64_MAX; }

  // Every device's clock held up until the next tile (GpuTiles::hold_clocks).
  void hold_clocks() {
    if (!holds_clocks() || released_) return;  // released: devices taken for good by tiles_done
    for (size_t d = 0; d < cdts_.size(); ++d) hold_clock(d);
  }

  // Device d's clock held up until the next tile, on a thread of its own (an earlier hold of d stopped first).
  void hold_clock(size_t d) {
    const std::lock_guard<std::mutex> lock(holding_mutex_);
    holding_[d] = std::jthread(
        [this, d, tiles = tiles_begun_.load()](std::stop_token stop) { spin_until_a_tile(d, tiles, stop); });
  }

  // From the first reserve (or device d's warm-up) to the first tile, spins that keep its clock up
  // (gpu/clock_hold), each holding the device for ~2 ms while nothing else does: the host's prepare takes
  // seconds, and a tile waits at most one spin. At most kHoldMs; a failure only logged. `tiles`: the tiles
  // begun when it was asked for.
  void spin_until_a_tile(size_t d, uint64_t tiles, const std::stop_token& stop) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto holding = [&] {
      return !stop.stop_requested() && tiles_begun_.load() == tiles && ms_since(t0) < kHoldMs;
    };
    size_t spins = 0;
    try {
      ClockHold hold(cdts_[d]->context());
      while (holding()) {
        if (!pool_.try_take(d)) {
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
          continue;
        }
        const DevicePool::Held held{pool_, d};
        if (!holding()) break;
        hold.spin(kSpinMs);
        ++spins;
      }
      spdlog::debug("device {}: clock held for {:.0f} ms ({} spins, the last of {} steps)", d, ms_since(t0), spins,
                    hold.steps());
    } catch (const std::exception& e) {
      spdlog::debug("device {}: clock held for {:.0f} ms ({} spins), then: {}", d, ms_since(t0), spins, e.what());
    }
  }

  // Device d's memory pool for tiles of `vertices` (Context::memory_pool), unless it has one (an earlier run's,
  // or a start's) or runs under a cap that counts the driver's allocations; a failure only logged (the buffers
  // then take memory of their own).
  void make_pool(size_t d, uint64_t vertices) {
    const Context& ctx = cdts_[d]->context();
    if (ctx.memory_pool.load() || ctx.memory_budget->limit) return;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      std::shared_ptr<DeviceMemoryPool> none, made = make_device_pool(ctx, vertices * kTileBytesPerPoint);
      const uint64_t bytes = made->bytes();
      if (ctx.memory_pool.compare_exchange_strong(none, std::move(made)))
        spdlog::debug("device {}: {:.1f} GB of device memory made ahead for tiles of {} points in {:.0f} ms", d,
                      bytes / 1e9, vertices, ms_since(t0));
    } catch (const std::exception& e) {
      spdlog::debug("device {}: no device memory pool for tiles of {} points: {}", d, vertices, e.what());
    }
  }

  // The first level's tiles are done (TileOptions::tiles_done): every slot but the first and every device but
  // the first are taken for good, and their staging, kept buffers and memory pools freed on a thread of its own,
  // beside the merge, which takes the slot and device left. The driver frees device memory at ~25 ms a GB and
  // pinned memory at ~55 ms a GB, one device after another (scripts/memory_probe.cpp), and a device call waits
  // for it: at 1B points on two devices those frees took 3.4-3.6 s after the writing, and freed at once beside the
  // merge, they held its device calls ~1 s. So one piece at a time (a pool's block, a slot), never while a call
  // runs (quiet()).
  void tiles_done() {
    if (released_.exchange(true) || staging_.size() < 2) return;
    releasing_ = std::jthread([this] {
      const auto t0 = std::chrono::steady_clock::now();
      uint64_t pool_bytes = 0, most_used = 0;
      size_t held = 0;
      // The slots first, then the devices: a merge that took another device's slot before this thread did holds
      // it while it waits for that device.
      for (size_t slot = 1; slot < staging_.size(); ++slot) slots_.take(slot);
      for (size_t d = 1; d < cdts_.size(); ++d) {
        pool_.take(d);
        if (pools_made_[d].valid()) pools_made_[d].wait();
        cdts_[d]->drop_kept();
        drop_temps(cdts_[d]->context());
        const std::shared_ptr<DeviceMemoryPool> memory = cdts_[d]->context().memory_pool.exchange(nullptr);
        if (!memory) continue;
        pool_bytes += memory->bytes();
        most_used = std::max(most_used, memory->most_in_use());
        // Buffers of the device's own (not kept between tiles) hold it to the device's close.
        if (memory.use_count() > 1) ++held;
        while (quiet() && memory->release_block()) {
        }
      }
      for (size_t slot = 1; slot < staging_.size(); ++slot) {
        if (reserved_[slot].valid()) reserved_[slot].wait();  // its pinning (and warm-up) done
        quiet();
        staging_[slot].reset();
      }
      spdlog::debug("tiles done: {} slot(s) and {:.0f} MB of {} device(s)' pools (at most {:.0f} MB a device in use) "
                    "freed beside the merge in {:.0f} ms{}",
                    staging_.size() - 1, pool_bytes / 1e6, cdts_.size() - 1, most_used / 1e6, ms_since(t0),
                    held ? ", " + std::to_string(held) + " held by buffers to their device's close" : "");
    });
  }

  // Waits while a call runs on a device (the merge; tiles of a later level); true.
  bool quiet() {
    std::unique_lock<std::mutex> lock(calls_mutex_);
    calls_done_.wait(lock, [&] { return calls_ == 0; });
    return true;
  }
  // Counts a device call for quiet(), from its start to its end.
  struct Call {
    OnDevice& on;
    explicit Call(OnDevice& o) : on(o) {
      const std::lock_guard<std::mutex> lock(on.calls_mutex_);
      ++on.calls_;
    }
    ~Call() {
      {
        const std::lock_guard<std::mutex> lock(on.calls_mutex_);
        --on.calls_;
      }
      on.calls_done_.notify_all();
    }
  };

  // Each slot's pinned memory freed on a thread of its own (0.2 s a 3 GB slot at 1B points), once the
  // reserve's threads that fill them are done.
  ~OnDevice() {
    if (releasing_.joinable()) releasing_.join();
    allocating_.clear();
    std::vector<std::jthread> freeing;
    for (std::unique_ptr<HostStaging>& slot : staging_) freeing.emplace_back([&slot] { slot.reset(); });
  }

  size_t warm_ups() const { return warm_ups_.load(); }

  // A tile in a slot of its own (a staging buffer; two a device, as many as the tiles in flight): its points are
  // written there and its final triangles copied out without the device, which is held only for the GPU part,
  // so those host copies overlap another tile's GPU work; so do the device's copies of them, on its copy queue.
  TileFinal staged(const TileJob& job) {
    tiles_begun_.fetch_add(1);
    return tbb::this_task_arena::isolate([&] {
      const auto t0 = std::chrono::steady_clock::now();
      const size_t slot = slots_.take_spread(cdts_.size());
      const DevicePool::Held held_slot{slots_, slot};
      const Call call(*this);
      const auto slot_taken = std::chrono::steady_clock::now();
      const size_t d = slot % cdts_.size();
      wait_reserved(slot, d);  // rethrows its allocation's error
      const auto t1 = std::chrono::steady_clock::now();
      const GpuCdt& cdt = *cdts_[d];
      HostStaging& staging = *staging_[slot];
      try {
        staging.fit(cdt.context(), GpuCdt::staging_bytes(job.ids.size()));
        const bool segments_sorted = GpuCdt::stage_points(job, staging);
        TileFinal f;
        GpuCdtStats one;
        const auto t2 = std::chrono::steady_clock::now();
        GpuCdt::TileUpload up = on_copy_queue(d, [&] { return cdt.upload_tile(job, staging, one); });
        up.segments_sorted = segments_sorted;
        const auto t3 = std::chrono::steady_clock::now();
        Buffer sorted;
        uint32_t count = 0;
        std::chrono::steady_clock::time_point t4;
        SubmitTally before, after;
        {
          pool_.take(d);
          const DevicePool::Held held_device{pool_, d};
          t4 = std::chrono::steady_clock::now();
          spdlog::debug("{}: waited {:.0f} ms for its staging memory, {:.0f} ms for a slot, staged in {:.0f} ms, "
                        "uploaded in {:.0f} ms, waited {:.0f} ms for the device",
                        job.what, ms(t1 - slot_taken), ms(slot_taken - t0), ms(t2 - t1), ms(t3 - t2), ms(t4 - t3));
          before = submit_tally();
          count = cdt.compute_tile(job, std::move(up), staging, f, sorted, one);
          after = submit_tally();
        }
        const auto t5 = std::chrono::steady_clock::now();
        on_copy_queue(d, [&] { cdt.download_tile(std::move(sorted), count, staging, one); });
        const auto t6 = std::chrono::steady_clock::now();
        GpuCdt::unstage_triangles(staging, count, job.ids, f);
        spdlog::debug("{}: device {} held from {:.0f} to {:.0f} ms ({} submits, {:.1f} ms waiting for them, GPU {:.1f} "
                      "ms), downloaded in {:.0f} ms, unstaged in {:.0f} ms",
                      job.what, d, ms(t4 - epoch_), ms(t5 - epoch_), after.submits - before.submits,
                      after.wait_ms - before.wait_ms, one.gpu_total_ms, ms(t6 - t5), ms_since(t6));
        if (sum_) add_up(one);
        return f;
      } catch (const DeviceError& e) {
        rethrow_named(e, job.what, job.ids.size(), job.segments.size(), d);
      }
    });
  }

  // f() on device d's copy queue: in turn with the queue's other copies where the device has one
  // (Context::copy_queue), else holding the device.
  template <class F>
  auto on_copy_queue(size_t d, F&& f) -> decltype(f()) {
    if (cdts_[d]->context().copy_queue) {
      const std::lock_guard<std::mutex> lock(*copying_[d]);
      return f();
    }
    pool_.take(d);
    const DevicePool::Held held{pool_, d};
    return f();
  }

  // A call in a slot (a merge, or a tile without a finalizer): its copies go through the slot's staging, pinned
  // beside the plan, so a tiled run's context pins none of its own (1 GiB for the merge, which held back the
  // tile devices' start: cli/gpu_start). The slot first, then its device, as for a staged tile.
  template <class Work>
  auto operator()(std::string_view what, size_t vertices, size_t segments, Work&& work) {
    // Isolated: a thread waiting inside the pipeline's own parallel loops must not pick up another tile,
    // which would wait for a device it holds.
    return tbb::this_task_arena::isolate([&] {
      const size_t slot = slots_.take_spread(cdts_.size());
      const DevicePool::Held held_slot{slots_, slot};
      const size_t d = slot % cdts_.size();
      pool_.take(d);
      const DevicePool::Held held{pool_, d};
      const Call call(*this);
      try {
        wait_reserved(slot, d);
        const StagingLent lent(cdts_[d]->context(), *staging_[slot]);
        GpuCdtStats one;
        auto result = work(*cdts_[d], one);
        if (sum_) add_up(one);
        return result;
      } catch (const DeviceError& e) {
        rethrow_named(e, what, vertices, segments, d);
      }
    });
  }

 private:
  static constexpr size_t kSlotsPerDevice = 2;
  // A device's memory pool for tiles, made ahead: ~232 bytes a point at 125M (29 GB) was a tile's peak, buffers
  // on the shelf included, without segments. With contour segments the pools grow in the first tiles to at most
  // 41.6 GB in use for tiles of 127M (~330 bytes a point, the pool's -v line); made at 400 ahead, they were no
  // faster and took longer to free (docs/tiles.md, session 63).
  static constexpr uint64_t kTileBytesPerPoint = 260;
  static constexpr double kHoldMs = 30'000, kSpinMs = 2;  // spin_until_a_tile's

  // e again, named by its tile (and device); still TooLarge where smaller tiles may fit.
  [[noreturn]] void rethrow_named(const DeviceError& e, std::string_view what, size_t vertices, size_t segments,
                                  size_t d) const {
    std::string m(what);
    m += " (" + std::to_string(vertices) + " vertices, " + std::to_string(segments) + " segments)";
    if (cdts_.size() > 1)
      m += " on device " + std::to_string(cdts_[d]->context().info.index) + " (" + cdts_[d]->context().info.name + ")";
    m += ": ";
    m += e.what();
    if (const auto* t = dynamic_cast<const TooLarge*>(&e)) throw TooLarge(m, t->need, t->limit);
    if (too_large(e)) throw TooLarge(m);
    throw DeviceError(m);
  }

  void add_up(const GpuCdtStats& one) {
    std::lock_guard<std::mutex> lock(sum_lock_);
    add(sum_->wall_ms, one.wall_ms);
    add(sum_->gpu_ms, one.gpu_ms);
    sum_->gpu_total_ms += one.gpu_total_ms;
    sum_->wall_total_ms += one.wall_total_ms;
    sum_->peak_device_bytes = std::max(sum_->peak_device_bytes, one.peak_device_bytes);
  }

  std::vector<const GpuCdt*> cdts_;
  const std::chrono::steady_clock::time_point epoch_ = std::chrono::steady_clock::now();  // the -v timeline's
  GpuCdtStats* sum_;
  const uint64_t warm_up_from_;
  const uint64_t pools_from_;
  std::atomic<size_t> warm_ups_{0};
  DevicePool pool_;   // the devices not running a call
  DevicePool slots_;  // the staging buffers not holding a tile; slot i is device i % devices'
  std::vector<std::unique_ptr<std::mutex>> copying_;  // a device's copy queue in use
  std::vector<std::unique_ptr<HostStaging>> staging_;
  uint64_t reserved_vertices_ = 0;                  // the largest reserve() so far
  std::atomic<uint64_t> tiles_begun_{0};  // tiles that asked for a slot: no warm-up after one; a clock hold ends
  std::vector<std::promise<void>> filled_;          // reserve()'s allocations, a slot each
  std::vector<std::shared_future<void>> reserved_;  // their futures, which a tile waits on
  std::vector<std::shared_future<void>> pools_made_;  // a device's memory pool, made by reserve() (if valid)
  std::mutex sum_lock_;
  std::mutex calls_mutex_;                 // quiet()'s
  std::condition_variable calls_done_;
  int calls_ = 0;                          // device calls running (Call)
  std::atomic<bool> released_{false};     // tiles_done() ran
  std::jthread releasing_;                 // its frees, joined first by the destructor
  std::vector<std::jthread> allocating_;  // joined before the slots it fills are freed
  std::mutex holding_mutex_;
  std::vector<std::jthread> holding_;  // spin_until_a_tile's, a device each; last: stopped and joined first
};

constexpr uint64_t kWarmUpOne = 100'000'000;     // warm_up_from: tiles of one device
constexpr uint64_t kWarmUpSeveral = 50'000'000;  // of each of several

}  // namespace

uint64_t warm_up_from(const std::vector<const GpuCdt*>& cdts) {
  for (const GpuCdt* c : cdts)
    if (c->context().info.type == "cpu") return UINT64_MAX;
  return cdts.size() > 1 ? kWarmUpSeveral : kWarmUpOne;
}

unsigned tile_ramp(const std::vector<const GpuCdt*>& cdts, uint64_t tile_points) {
  return tile_points >= std::max(kWarmUpOne, warm_up_from(cdts)) ? 2 : 0;
}

uint64_t device_pools_from(const std::vector<const GpuCdt*>& cdts) {
  for (const GpuCdt* c : cdts)
    if (c->context().info.type == "cpu") return UINT64_MAX;
  return 8'000'000;
}

GpuTiles gpu_tiles(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum, bool device_pools) {
  const uint64_t warm = warm_up_from(cdts), pools = device_pools ? device_pools_from(cdts) : UINT64_MAX;
  return gpu_tiles(std::move(cdts), sum, warm, pools);
}

GpuTiles gpu_tiles(std::vector<const GpuCdt*> cdts, GpuCdtStats* sum, uint64_t warm_up_from,
                   uint64_t pools_from) {
  auto on = std::make_shared<OnDevice>(std::move(cdts), sum, warm_up_from, pools_from);
  GpuTiles g;
  // A tile is a resolved graph already: no resolve stage, no copies.
  g.triangulate = [on](const Points& vertices, const std::vector<Edge>& segments, std::string_view what) {
    return (*on)(what, vertices.size(), segments.size(), [&](const GpuCdt& cdt, GpuCdtStats& one) {
      return TileMesh{cdt.triangulate_graph(vertices, segments, &one), {}};
    });
  };
  g.finalize = [on](const TileJob& job) { return on->staged(job); };
  g.reserve = [on](uint64_t vertices) { on->reserve(vertices); };
  g.warm_ups = [on] { return on->warm_ups(); };
  g.tiles_done = [on] { on->tiles_done(); };
  g.hold_clocks = [on] { on->hold_clocks(); };
  return g;
}

TileDevices::~TileDevices() {
  std::vector<std::jthread> closing;
  for (size_t i = 0; i < opened_.size(); ++i)
    closing.emplace_back([this, i] {
      opened_cdts_[i].reset();  // its passes and buffers before the context
      opened_[i].reset();
    });
}

void TileDevices::borrow(const GpuCdt& cdt) { cdts_.push_back(&cdt); }

void TileDevices::open(const std::vector<size_t>& indices, const ContextOptions& options) {
  for (auto& ctx : create_contexts(indices, options)) {
    opened_cdts_.push_back(std::make_unique<GpuCdt>(*ctx));
    cdts_.push_back(opened_cdts_.back().get());
    opened_.push_back(std::move(ctx));
  }
}

uint64_t TileDevices::max_tile_points() const {
  uint64_t smallest = UINT64_MAX;
  for (const GpuCdt* c : cdts_) smallest = std::min(smallest, gpu::max_tile_points(c->context()));
  return smallest;
}

std::string TileDevices::names() const {
  std::string names;
  for (const GpuCdt* c : cdts_)
    names += (names.empty() ? "" : ", ") + c->context().info.name + " (" + std::to_string(c->context().info.index) + ")";
  return names;
}

namespace {
// The Delaunay build's slot limit, in points: every device's.
constexpr uint64_t kSlotPoints = DT_MAX_SLOTS / 2;
// A quarter to spare for the endpoints of the segments that cross into a tile.
uint64_t with_room(uint64_t points) { return points / 4 * 3; }
}  // namespace

uint64_t max_tile_points_of_any_device() { return with_room(kSlotPoints); }

uint64_t max_tile_points(const Context& ctx) {
  uint64_t device_local = 0;
  for (size_t h = 0; h < ctx.info.heap_sizes.size(); ++h)
    if (ctx.info.heap_device_local[h]) device_local = std::max(device_local, ctx.info.heap_sizes[h]);
  constexpr uint64_t kBytesPerPoint = 260;
  const uint64_t by_memory = device_local / kBytesPerPoint;
  // The largest descriptor-bound buffer per point: the constraint inserter's 12-byte tables per triangle
  // slot, ~24 bytes a point (6.1 GB at 256M points, refused by a 4 GiB range).
  const uint64_t by_range = ctx.info.max_storage_buffer_range / 24;
  return with_room(std::min({by_memory, kSlotPoints, by_range}));
}

}  // namespace cdtgpu::gpu
