// Tiles run by other processes (MPI ranks, issue 29; cli/mpi.cpp carries them): the process that plans and merges
// hands a tile to a worker as it would to one of its devices. The worker gets the tile's vertices and segments
// only, runs its own finalizer (its GPU's, or CGAL and the host's test) and answers with the tile's final
// triangles, border and splits in the tile's ids; the tile's TileJob ids map them back here. So a worker holds
// its tiles in flight, never the whole input, and a tile's result does not depend on where it ran.
//
//   TileWorkers workers{.slots = {2, 2}, .run = [&](unsigned w, unsigned slot, const TileWork& work) { ... }};
//   opt.finalize = with_workers(gpu_tiles.finalize, 2 * devices, workers);
//   opt.tiles_in_flight = 2 * devices + workers.total_slots();
//
//   // at a worker:
//   TileWork work = ...received...;
//   TileFinal f = finalize(work.job());
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <numeric>
#include <string>
#include <vector>

#include "core/tiles.hpp"

namespace cdtgpu {

// A tile as it travels: its vertices (the whole's at the job's ids, in order), its segments in their indices.
struct TileWork {
  Points vertices;
  std::vector<Edge> segments;
  TileRect rect;
  std::string what;
  bool unresolved = false;
  std::vector<uint32_t> ids;  // 0, 1, ...: the tile is the worker's whole input; made by job()

  // Where a TileFinalizer reads it. The result is in the tile's own ids (global_ids, if set, means those too).
  TileJob job();
};
// The tile of `job` as it travels (its vertices gathered on all cores).
TileWork tile_work(const TileJob& job);

struct TileWorkers {
  // Tiles worker w takes at once (slots[w]); a worker with none takes no tile.
  std::vector<unsigned> slots;
  // Runs a tile at worker w in slot `slot` (one call a slot at a time) and gives its TileFinal in the tile's ids;
  // throws what the worker's tile threw (UnresolvedTile, a device's error).
  std::function<TileFinal(unsigned w, unsigned slot, const TileWork& work)> run;

  unsigned total_slots() const { return std::accumulate(slots.begin(), slots.end(), 0u); }
};

// The processes of one run (MPI ranks; cli/mpi.cpp): rank 0 reads the joined input, plans, merges and writes; every
// other rank is a worker that runs the tiles rank 0 hands it.
struct RankTiles {
  int rank = 0, ranks = 1;
  // Rank 0: the other ranks as workers, for GPU tiles (`gpu`) or the host's (CGAL and the final test); their slots
  // are what each said when it began to serve (a worker without a GPU takes no GPU tile).
  std::function<TileWorkers(bool gpu)> workers;
  // Rank 0: no more tiles; every worker returns from `serve`. Called once the triangulation is done. Returns how
  // many tiles the workers ran.
  std::function<uint64_t()> end;
  // A worker: says it takes `gpu_slots` GPU tiles and `host_slots` host tiles at once, then runs each tile it is
  // sent through `finalize` (gpu: its GPU's) until rank 0 ends them. A tile that fails other than by an
  // UnresolvedTile or a device's error ends the run.
  std::function<void(unsigned gpu_slots, unsigned host_slots,
                     const std::function<TileFinal(bool gpu, const TileJob& job)>& finalize)>
      serve;
};

// The GPUs a run's tiles spread over (auto_gpu_tile_points): this process's `local` ones and, at rank 0 of an MPI
// run, the other ranks' (two GPU slots a device, as serve() is told). Counting rank 0's alone, ranks bound one to
// a GPU planned tiles for one device: ~10 tiles of 134M at 1B points for every GPU of a cluster.
inline size_t run_gpu_devices(size_t local, const RankTiles* ranks) {
  if (!ranks || ranks->rank != 0 || !ranks->workers) return local;
  return local + ranks->workers(true).total_slots() / 2;
}

// The same before the other ranks have said what they take (every rank's devices, staging and pools are made
// while rank 0 reads and prepares): each rank counted with this process's `local` GPUs, as ranks bound one to a
// GPU, or one to a host of like GPUs, have them. Since tiles shrink with the devices (a twelfth of the input a
// device; a sixteenth then), a rank that counted its own alone made pools and staging for tiles ~8 times too
// large on two ranks.
inline size_t expected_gpu_devices(size_t local, const RankTiles* ranks) {
  return ranks ? local * size_t(std::max(ranks->ranks, 1)) : local;
}

// A finalizer that runs each tile here (`local`, at most `local_slots` at once) or at a free worker slot, a
// worker's first: so run local_slots + workers.total_slots() tiles in flight, on as many threads (a tile at a
// worker holds its thread while it waits: TileOptions::waiting_threads). A worker's results come in the job's
// local ids (global_ids false), `local`'s as `local` gives them.
TileFinalizer with_workers(TileFinalizer local, unsigned local_slots, TileWorkers workers);

}  // namespace cdtgpu
