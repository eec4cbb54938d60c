#include "cli/mpi.hpp"

#include "core/parallel.hpp"
#include "core/timing.hpp"
#include "core/touched.hpp"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <future>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>

#include <spdlog/spdlog.h>

#include "core/uninit.hpp"
#include "gpu/check.hpp"

#ifdef CDTGPU_MPI
#include <mpi.h>
#endif

namespace cdtgpu {

namespace {

// The launcher's word for how many processes it started: Open MPI's mpirun, or a PMI / PMIx launcher (srun).
int launched_ranks() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* v = std::getenv(var)) return std::max(1, std::atoi(v));
  return std::getenv("PMIX_RANK") ? 2 : 1;  // PMIx without a size: several, say so
}

#ifdef CDTGPU_MPI
// Bytes point to point, in pieces a 32-bit MPI count takes.
constexpr int kTilesTag = 3;
constexpr uint64_t kPiece = uint64_t(1) << 30;
void send_pieces(const void* p, uint64_t n, int to, int tag) {
  for (uint64_t at = 0; at < n; at += kPiece)
    MPI_Send(static_cast<const char*>(p) + at, int(std::min(kPiece, n - at)), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}
void recv_pieces(void* p, uint64_t n, int from, int tag) {
  for (uint64_t at = 0; at < n; at += kPiece)
    MPI_Recv(static_cast<char*>(p) + at, int(std::min(kPiece, n - at)), MPI_BYTE, from, tag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
}
// The same, the receiver learning the size first.
void send_bytes(const void* p, uint64_t n, int to, int tag = kTilesTag) {
  MPI_Send(&n, 1, MPI_UINT64_T, to, tag, MPI_COMM_WORLD);
  send_pieces(p, n, to, tag);
}
// A list of n elements, as one piece after another.
template <typename Vec>
void send_list(const Vec& v, int to, int tag) {
  send_pieces(v.data(), v.size() * sizeof(v[0]), to, tag);
}
template <typename Vec>
void recv_list(Vec& v, uint64_t n, int from, int tag) {
  // Touched first on all cores: MPI's receive faulting fresh pages in ran at ~1.5 GB/s, touched ones ~4.
  if constexpr (std::is_same_v<Vec, std::string>)
    v.resize(n);
  else
    resize_touched(v, n);
  recv_pieces(v.data(), n * sizeof(v[0]), from, tag);
}
template <typename Vec>
void recv_into(Vec& v, int from, int tag = kTilesTag) {
  uint64_t n = 0;
  MPI_Recv(&n, 1, MPI_UINT64_T, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  recv_list(v, n / sizeof(v[0]), from, tag);
}

// Tiles handed out by rank 0 (core/tile_workers.hpp). Each worker slot has a tag of its own for its tiles and
// one for their answers, so a slot's messages never meet another's: rank 0 calls from a thread a tile, a worker
// answers from a thread a tile (MPI_THREAD_MULTIPLE).
constexpr int kHelloTag = 5, kJobTag = 1000, kAnswerTag = 20000;  // + the slot
struct JobHead {
  uint64_t end = 0, gpu = 0, unresolved = 0;
  uint64_t vertices = 0, segments = 0, what = 0;
  double rect[4] = {};
};
struct AnswerHead {
  enum : uint64_t { ok, unresolved, too_large, device };
  uint64_t status = ok;
  uint64_t lengths[3] = {};  // final triangles, border edges, splits
  uint64_t message = 0;
  double need = 0, limit = 0;  // too_large: gpu::TooLarge's
};

// Waits for a message without holding a core: the other side may be a second into a tile. MPI's blocking calls
// spin, and a rank has a thread waiting so for every tile it has out.
MPI_Status await_message(int from, int tag) {
  MPI_Status status;
  for (;;) {
    int there = 0;
    MPI_Iprobe(from, tag, MPI_COMM_WORLD, &there, &status);
    if (there) return status;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

// Rank 0: a tile at `rank`, in its `slot`; the worker's failure thrown here as the worker caught it.
TileFinal run_at(int rank, unsigned slot, const TileWork& work, bool gpu) {
  JobHead h;
  h.gpu = gpu, h.unresolved = work.unresolved;
  h.vertices = work.vertices.size(), h.segments = work.segments.size(), h.what = work.what.size();
  const double rect[4] = {work.rect.x0, work.rect.x1, work.rect.y0, work.rect.y1};
  std::copy(rect, rect + 4, h.rect);
  const int tag = kJobTag + int(slot), answer = kAnswerTag + int(slot);
  MPI_Send(&h, int(sizeof h), MPI_BYTE, rank, tag, MPI_COMM_WORLD);
  send_list(work.vertices, rank, tag);
  send_list(work.segments, rank, tag);
  send_list(work.what, rank, tag);
  await_message(rank, answer);
  AnswerHead a;
  MPI_Recv(&a, int(sizeof a), MPI_BYTE, rank, answer, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  TileFinal f;
  recv_list(f.triangles, a.lengths[0], rank, answer);
  recv_list(f.border, a.lengths[1], rank, answer);
  recv_list(f.split, a.lengths[2], rank, answer);
  std::string message;
  recv_list(message, a.message, rank, answer);
  if (a.status == AnswerHead::unresolved) throw UnresolvedTile(message);
  if (a.status == AnswerHead::too_large) throw gpu::TooLarge(message, a.need, a.limit);
  if (a.status == AnswerHead::device) throw gpu::DeviceError(message);
  return f;
}

// A worker's answer to rank 0: the tile's results, or why it failed where rank 0 can act on it (an input to
// resolve first, smaller tiles, the CPU). Any other failure ends the run from here.
void answer(int rank, unsigned slot, TileWork& work, bool gpu,
            const std::function<TileFinal(bool gpu, const TileJob& job)>& finalize) {
  AnswerHead a;
  TileFinal f;
  std::string message;
  try {
    f = finalize(gpu, work.job());
  } catch (const UnresolvedTile& e) {
    a.status = AnswerHead::unresolved, message = e.what();
  } catch (const gpu::DeviceError& e) {
    a.status = gpu::too_large(e) ? AnswerHead::too_large : AnswerHead::device, message = e.what();
    if (const auto* t = dynamic_cast<const gpu::TooLarge*>(&e)) a.need = t->need, a.limit = t->limit;
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", work.what, e.what());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  // Fault injection for the tests: this rank dies before it hands back a tile.
  if (const char* kill = std::getenv("CDTGPU_MPI_TEST_KILL_RANK"); kill && std::atoi(kill) == rank)
    std::raise(SIGKILL);
  free_storage(work.vertices);
  a.lengths[0] = f.triangles.size(), a.lengths[1] = f.border.size(), a.lengths[2] = f.split.size();
  a.message = message.size();
  const int tag = kAnswerTag + int(slot);
  MPI_Send(&a, int(sizeof a), MPI_BYTE, 0, tag, MPI_COMM_WORLD);
  send_list(f.triangles, 0, tag);
  send_list(f.border, 0, tag);
  send_list(f.split, 0, tag);
  send_list(message, 0, tag);
}

// A worker: says its slots, then takes each tile on a thread of its own until rank 0's end. `threads`: whether MPI
// takes calls from several threads at once; without, the worker said it has no slots and only waits for the end.
void serve(int rank, bool threads, unsigned gpu_slots, unsigned host_slots,
           const std::function<TileFinal(bool gpu, const TileJob& job)>& finalize) {
  const uint64_t hello[2] = {threads ? gpu_slots : 0, threads ? host_slots : 0};
  MPI_Send(hello, 2, MPI_UINT64_T, 0, kHelloTag, MPI_COMM_WORLD);
  std::vector<std::future<void>> running;
  for (;;) {
    // Rank 0 sends nothing else before its end (--tiles-out's pieces come after it, and MPI keeps their order).
    const int tag = await_message(0, MPI_ANY_TAG).MPI_TAG;
    if (tag < kJobTag || tag >= kAnswerTag) {
      spdlog::error("a message with tag {} from rank 0 where a tile was expected", tag);
      MPI_Abort(MPI_COMM_WORLD, 3);
    }
    JobHead h;
    MPI_Recv(&h, int(sizeof h), MPI_BYTE, 0, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (h.end) break;
    auto work = std::make_shared<TileWork>();
    recv_list(work->vertices, h.vertices, 0, tag);
    recv_list(work->segments, h.segments, 0, tag);
    recv_list(work->what, h.what, 0, tag);
    work->rect = {h.rect[0], h.rect[1], h.rect[2], h.rect[3]};
    work->unresolved = h.unresolved != 0;
    std::erase_if(running, [](std::future<void>& f) {
      return f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    });
    const unsigned slot = unsigned(tag - kJobTag);
    running.push_back(std::async(std::launch::async, [=, &finalize] { answer(rank, slot, *work, h.gpu != 0, finalize); }));
  }
  for (std::future<void>& f : running) f.get();
}

// Rank 0's side: the workers' slots, learnt once from what each said when it began to serve.
class Workers {
 public:
  Workers(int ranks, bool threads) : ranks_(ranks), threads_(threads) {}
  TileWorkers of(bool gpu) {
    hear();
    TileWorkers w;
    w.slots = gpu ? gpu_slots_ : host_slots_;
    w.run = [this, gpu](unsigned worker, unsigned slot, const TileWork& work) {
      TileFinal f = run_at(int(worker) + 1, slot, work, gpu);
      ++handed_;
      return f;
    };
    return w;
  }
  uint64_t end() {
    hear();
    if (!ended_) {
      ended_ = true;
      JobHead h;
      h.end = 1;
      for (int r = 1; r < ranks_; ++r) MPI_Send(&h, int(sizeof h), MPI_BYTE, r, kJobTag, MPI_COMM_WORLD);
    }
    return handed_;
  }

 private:
  void hear() {
    std::call_once(heard_, [this] {
      for (int r = 1; r < ranks_; ++r) {
        uint64_t hello[2];
        await_message(r, kHelloTag);
        MPI_Recv(hello, 2, MPI_UINT64_T, r, kHelloTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        gpu_slots_.push_back(unsigned(hello[0]));
        host_slots_.push_back(unsigned(hello[1]));
      }
      if (!threads_) spdlog::warn("this MPI gives no MPI_THREAD_MULTIPLE: rank 0 runs every tile itself");
    });
  }
  const int ranks_;
  const bool threads_;
  std::once_flag heard_;
  bool ended_ = false;
  std::atomic<uint64_t> handed_{0};  // tiles the workers ran
  std::vector<unsigned> gpu_slots_, host_slots_;
};

// --tiles-out's files written by every rank (io/tiles_dir.hpp): rank 0 hands each rank its pieces.
TilesDirSharing tiles_dir_sharing(int rank, int ranks, const std::string& host, std::atomic<bool>& others_done) {
  TilesDirSharing s;
  s.rank = rank;
  s.ranks = ranks;
  s.send = [](int to, const std::string& fresh, const Crs& crs,
              const std::vector<std::pair<size_t, const MeshPiece*>>& pieces) {
    send_bytes(fresh.data(), fresh.size(), to);
    const int64_t numbers[5] = {crs.projected, crs.from_geographic, crs.epsg, crs.zone, crs.north};
    send_bytes(numbers, sizeof numbers, to);
    send_bytes(crs.name.data(), crs.name.size(), to);
    send_bytes(crs.wkt.data(), crs.wkt.size(), to);
    const uint64_t n = pieces.size();
    send_bytes(&n, sizeof n, to);
    for (const auto& [t, piece] : pieces) {
      const double head[5] = {double(t), piece->x0, piece->y0, piece->x1, piece->y1};
      send_bytes(head, sizeof head, to);
      send_bytes(piece->mesh.vertices.data(), piece->mesh.vertices.size() * sizeof(Point3), to);
      send_bytes(piece->mesh.triangles.data(), piece->mesh.triangles.size() * sizeof(Triangle), to);
    }
  };
  s.receive = [] {
    TilesDirSharing::Handed got;
    recv_into(got.fresh, 0);
    std::vector<int64_t> numbers;
    recv_into(numbers, 0);
    Crs& crs = got.crs;
    crs.projected = numbers.at(0) != 0, crs.from_geographic = numbers.at(1) != 0;
    crs.epsg = int(numbers.at(2)), crs.zone = int(numbers.at(3)), crs.north = numbers.at(4) != 0;
    recv_into(crs.name, 0);
    recv_into(crs.wkt, 0);
    std::vector<uint64_t> n;
    recv_into(n, 0);
    for (uint64_t k = 0; k < n.at(0); ++k) {
      std::vector<double> head;
      recv_into(head, 0);
      MeshPiece piece;
      piece.x0 = head.at(1), piece.y0 = head.at(2), piece.x1 = head.at(3), piece.y1 = head.at(4);
      recv_into(piece.mesh.vertices, 0);
      recv_into(piece.mesh.triangles, 0);
      got.pieces.emplace_back(size_t(head[0]), std::move(piece));
    }
    return got;
  };
  s.outcomes = [rank, ranks, host, &others_done](const std::string& mine) {
    const std::string said = mine.empty() ? "" : "rank " + std::to_string(rank) + " on " + host + ": " + mine;
    std::vector<std::string> all;
    if (rank != 0) {
      send_bytes(said.data(), said.size(), 0);
      return all;
    }
    all.push_back(said);
    for (int r = 1; r < ranks; ++r) recv_into(all.emplace_back(), r);
    others_done = true;  // every other rank has said its last word and only finalises
    return all;
  };
  return s;
}

// Every reader's bytes to the first (rank 0), in their order: each sends its own, the first receives them all at
// once (nonblocking, in pieces a 32-bit MPI count takes), copying its own into place meanwhile.
void gather_bytes(const char* mine, char* all, const std::vector<uint64_t>& sizes, int rank, MPI_Comm comm) {
  constexpr int kShareTag = 4;
  std::vector<MPI_Request> requests;
  auto pieces = [&](uint64_t n, auto&& post) {
    for (uint64_t done = 0; done < n; done += kPiece) post(done, int(std::min(kPiece, n - done)));
  };
  if (rank != 0) {
    pieces(sizes[size_t(rank)], [&](uint64_t at, int n) {
      MPI_Isend(mine + at, n, MPI_BYTE, 0, kShareTag, comm, &requests.emplace_back());
    });
  } else {
    uint64_t at = sizes[0];
    for (int r = 1; r < int(sizes.size()); ++r) {
      pieces(sizes[size_t(r)], [&](uint64_t done, int n) {
        MPI_Irecv(all + at + done, n, MPI_BYTE, r, kShareTag, comm, &requests.emplace_back());
      });
      at += sizes[size_t(r)];
    }
    copy_on_all_cores(mine, sizes[0], all);
  }
  MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
}
#endif

// The launcher's binding against this rank's share of the host: sched_getaffinity's CPUs against the host's
// online CPUs (CDTGPU_HOST_CPUS stands for them in tests) over the ranks on the host.
[[maybe_unused]] std::string binding_note(int local_ranks) {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return "";
  const long bound = CPU_COUNT(&set);
  long host = sysconf(_SC_NPROCESSORS_ONLN);
  if (const char* v = std::getenv("CDTGPU_HOST_CPUS"); v && *v) host = std::atol(v);
  const long share = host / std::max(1, local_ranks);
  if (bound * 2 > share) return "";
  return "this rank may use " + std::to_string(bound) + " of the host's " + std::to_string(host) + " CPUs (" +
         std::to_string(local_ranks) + " ranks on it could use " + std::to_string(share) +
         " each): the launcher bound it. Every stage runs on those CPUs only; give mpirun --bind-to none "
         "(Open MPI binds each rank to one core when -n is 2 or less), or srun --cpus-per-task";
}

}  // namespace

MpiSession::MpiSession(int* argc, char*** argv) {
  char name[256] = {};
  gethostname(name, sizeof name - 1);
  host_ = name;
  const int launched = launched_ranks();
  for (const char* var : {"OMPI_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID", "MPI_LOCALRANKID", "PMIX_LOCAL_RANK"})
    if (const char* v = std::getenv(var)) {
      local_rank_ = std::atoi(v);
      break;
    }
#ifdef CDTGPU_MPI
  if (launched > 1) {
    // Rank 0 hands out tiles from a thread a tile and a worker answers from a thread a tile: MPI must take calls
    // from several threads at once. The mesh's writer thread calls MPI too (--tiles-out's files shared).
    int provided = 0;
    const auto t0 = std::chrono::steady_clock::now();
    MPI_Init_thread(argc, argv, MPI_THREAD_MULTIPLE, &provided);
    init_ms_ = ms_since(t0);
    initialised_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &tiles_.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &tiles_.ranks);
    const int rank = tiles_.rank, ranks = tiles_.ranks;
    const bool threads = provided >= MPI_THREAD_MULTIPLE;
    auto workers = std::make_shared<Workers>(ranks, threads);
    tiles_.workers = [workers](bool gpu) { return workers->of(gpu); };
    tiles_.end = [workers] { return workers->end(); };
    tiles_.serve = [rank, threads](unsigned gpu_slots, unsigned host_slots, const auto& finalize) {
      serve(rank, threads, gpu_slots, host_slots, finalize);
    };
    if (provided >= MPI_THREAD_SERIALIZED) tiles_dir_ = tiles_dir_sharing(rank, ranks, host_, others_done_);
    MPI_Comm here;
    int local = 1, local_rank = 0;
    if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &here) == MPI_SUCCESS) {
      MPI_Comm_size(here, &local);
      MPI_Comm_rank(here, &local_rank);
      MPI_Comm_free(&here);
    }
    local_ranks_ = local;
    // The readers: the first rank of each host, whose share is the host's (its cores and disks are the other
    // ranks' too: on one host rank 0 read 100M LAS points alone in 0.37 s, half of them and the other half
    // received in 0.63 s), or every rank with CDTGPU_READ_SHARES=ranks. Rank 0 is the first of its host.
    const char* by = std::getenv("CDTGPU_READ_SHARES");
    const bool reader = (by && std::string(by) == "ranks") || local_rank == 0;
    MPI_Comm comm = MPI_COMM_NULL;
    MPI_Comm_split(MPI_COMM_WORLD, reader ? 0 : MPI_UNDEFINED, rank, &comm);
    int readers = 0, index = 0;
    if (reader) {
      MPI_Comm_size(comm, &readers);
      MPI_Comm_rank(comm, &index);
      readers_ = std::shared_ptr<void>(new MPI_Comm(comm), [](void* p) {
        MPI_Comm_free(static_cast<MPI_Comm*>(p));
        delete static_cast<MPI_Comm*>(p);
      });
    }
    if (readers > 1) {
      read_share_.index = uint32_t(index);
      read_share_.count = uint32_t(readers);
      read_share_.all_sizes = [readers, comm](uint64_t mine) {
        std::vector<uint64_t> all(size_t(readers), 0);
        MPI_Allgather(&mine, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, comm);
        return all;
      };
      read_share_.gather_bytes = [index, comm](const char* mine, char* all, const std::vector<uint64_t>& sizes) {
        cdtgpu::gather_bytes(mine, all, sizes, index, comm);
      };
    }
    cpu_note_ = binding_note(local);
  }
#else
  (void)argc;
  (void)argv;
  if (launched > 1)
    refusal_ = "started as one of " + std::to_string(launched) +
               " processes (mpirun or srun), but this cdtgpu was built without MPI: it would run the whole job " +
               std::to_string(launched) + " times. Install Open MPI (libopenmpi-dev) and rebuild, or run it alone";
#endif
}

MpiSession::~MpiSession() {
#ifdef CDTGPU_MPI
  readers_.reset();
  if (!initialised_) return;
  const auto t0 = std::chrono::steady_clock::now();
  MPI_Finalize();
  spdlog::debug("MPI_Finalize: {:.1f} ms", ms_since(t0));
#endif
}

void MpiSession::abort(int code) const {
#ifdef CDTGPU_MPI
  if (initialised_) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

}  // namespace cdtgpu
