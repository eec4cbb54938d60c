#include "core/tile_workers.hpp"

#include <tbb/parallel_for.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>

#include "core/touched.hpp"

namespace cdtgpu {

TileJob TileWork::job() {
  if (ids.size() != vertices.size()) {
    ids.resize(vertices.size());
    std::iota(ids.begin(), ids.end(), 0u);
  }
  return TileJob{vertices, ids, segments, rect, what, unresolved};
}

TileWork tile_work(const TileJob& job) {
  TileWork w;
  resize_unwritten(w.vertices, job.ids.size());
  tbb::parallel_for(size_t(0), job.ids.size(), [&](size_t i) { w.vertices[i] = job.all[job.ids[i]]; });
  w.segments.assign(job.segments.begin(), job.segments.end());
  w.rect = job.rect;
  w.what = std::string(job.what);
  w.unresolved = job.unresolved;
  return w;
}

TileFinalizer with_workers(TileFinalizer local, unsigned local_slots, TileWorkers workers) {
  struct Slots {
    std::mutex mutex;
    std::condition_variable freed;
    unsigned local_busy = 0;
    std::vector<std::vector<bool>> busy;  // [worker][slot]
  };
  auto slots = std::make_shared<Slots>();
  for (unsigned n : workers.slots) slots->busy.emplace_back(n, false);
  return [local = std::move(local), local_slots, workers = std::move(workers), slots](const TileJob& job) {
    // A free slot, a worker's first (they hold nothing else to do); nullopt: here.
    std::optional<std::pair<unsigned, unsigned>> at;
    {
      std::unique_lock<std::mutex> lock(slots->mutex);
      slots->freed.wait(lock, [&] {
        for (unsigned w = 0; w < slots->busy.size() && !at; ++w)
          for (unsigned s = 0; s < slots->busy[w].size() && !at; ++s)
            if (!slots->busy[w][s]) at.emplace(w, s);
        return at || slots->local_busy < std::max(1u, local_slots);
      });
      if (at)
        slots->busy[at->first][at->second] = true;
      else
        ++slots->local_busy;
    }
    struct Release {
      Slots& s;
      std::optional<std::pair<unsigned, unsigned>> at;
      ~Release() {
        {
          std::lock_guard<std::mutex> lock(s.mutex);
          if (at)
            s.busy[at->first][at->second] = false;
          else
            --s.local_busy;
        }
        s.freed.notify_all();
      }
    } release{*slots, at};
    if (!at) return local(job);
    TileFinal f = workers.run(at->first, at->second, tile_work(job));
    f.global_ids = false;
    return f;
  };
}

}  // namespace cdtgpu
