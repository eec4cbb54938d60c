#include "cli/mpi.hpp"

#include "core/parallel.hpp"
#include "core/touched.hpp"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstring>
#include <cstdlib>
#include <string>
#include <type_traits>

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
template <typename Vec>
void recv_into(Vec& v, int from, int tag = kTilesTag) {
  uint64_t n = 0;
  MPI_Recv(&n, 1, MPI_UINT64_T, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  // Touched first on all cores: MPI's receive faulting fresh pages in ran at ~1.5 GB/s, touched ones ~4.
  if constexpr (std::is_same_v<Vec, std::string>)
    v.resize(n);
  else
    resize_touched(v, n / sizeof(v[0]));
  recv_pieces(v.data(), n, from, tag);
}

// A tile's results to rank 0 (TileSharing): the message, then each list's bytes in pieces a 32-bit MPI count
// takes. The message comes from any rank, its lists from that rank only, on a tag of their own.
constexpr int kTileMessageTag = 1, kTileListTag = 2;
void send_tile(const TileMessage& m, const TileLists& lists, int rank) {
  // Fault injection for the tests: this rank dies before handing over its tiles.
  if (const char* kill = std::getenv("CDTGPU_MPI_TEST_KILL_RANK"); kill && std::atoi(kill) == rank)
    std::raise(SIGKILL);
  MPI_Send(&m, int(sizeof m), MPI_BYTE, 0, kTileMessageTag, MPI_COMM_WORLD);
  for (const auto& list : lists) send_pieces(list.data(), list.size(), 0, kTileListTag);
}
void receive_tiles(int ranks, const std::function<TileLists(const TileMessage&)>& where,
                   const std::function<void(const TileMessage&)>& got) {
  for (int open = ranks - 1; open > 0;) {
    TileMessage m;
    MPI_Status status;
    MPI_Recv(&m, int(sizeof m), MPI_BYTE, MPI_ANY_SOURCE, kTileMessageTag, MPI_COMM_WORLD, &status);
    if (m.tile == TileMessage::kDone) {
      --open;
      got(m);
      continue;
    }
    for (const auto& list : where(m)) recv_pieces(list.data(), list.size(), status.MPI_SOURCE, kTileListTag);
    got(m);
  }
}

// --tiles-out's files written by every rank (io/tiles_dir.hpp): rank 0 hands each rank its pieces.
TilesDirSharing tiles_dir_sharing(int rank, int ranks, const std::string& host, std::atomic<bool>& others_done) {
  TilesDirSharing s;
  s.rank = rank;
  s.ranks = ranks;
  s.send = [](int to, const std::string& fresh, const std::vector<std::pair<size_t, const MeshPiece*>>& pieces) {
    send_bytes(fresh.data(), fresh.size(), to);
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
    std::pair<std::string, std::vector<std::pair<size_t, MeshPiece>>> got;
    recv_into(got.first, 0);
    std::vector<uint64_t> n;
    recv_into(n, 0);
    for (uint64_t k = 0; k < n.at(0); ++k) {
      std::vector<double> head;
      recv_into(head, 0);
      MeshPiece piece;
      piece.x0 = head.at(1), piece.y0 = head.at(2), piece.x1 = head.at(3), piece.y1 = head.at(4);
      recv_into(piece.mesh.vertices, 0);
      recv_into(piece.mesh.triangles, 0);
      got.second.emplace_back(size_t(head[0]), std::move(piece));
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

// Every rank's bytes to every rank, in rank order: each rank sends its own to every other and receives theirs, all
// at once (nonblocking, in pieces a 32-bit MPI count takes), copying its own into place meanwhile. Broadcast one
// rank after another, the transfers did not overlap.
void all_bytes(const char* mine, char* all, const std::vector<uint64_t>& sizes, int rank) {
  constexpr int kShareTag = 4;
  std::vector<uint64_t> at(sizes.size() + 1, 0);
  for (size_t r = 0; r < sizes.size(); ++r) at[r + 1] = at[r] + sizes[r];
  std::vector<MPI_Request> requests;
  for (int r = 0; r < int(sizes.size()); ++r) {
    if (r == rank) continue;
    for (uint64_t done = 0; done < sizes[size_t(r)]; done += kPiece)
      MPI_Irecv(all + at[size_t(r)] + done, int(std::min(kPiece, sizes[size_t(r)] - done)), MPI_BYTE, r, kShareTag,
                MPI_COMM_WORLD, &requests.emplace_back());
    for (uint64_t done = 0; done < sizes[size_t(rank)]; done += kPiece)
      MPI_Isend(mine + done, int(std::min(kPiece, sizes[size_t(rank)] - done)), MPI_BYTE, r, kShareTag,
                MPI_COMM_WORLD, &requests.emplace_back());
  }
  copy_on_all_cores(mine, sizes[size_t(rank)], all + at[size_t(rank)]);
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
    // One thread at a time calls MPI: the main thread, or the one writing the mesh beside the derived outputs
    // (--tiles-out's files shared among the ranks).
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided);
    initialised_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &sharing_.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &sharing_.ranks);
    const int rank = sharing_.rank, ranks = sharing_.ranks;
    sharing_.send = [rank](const TileMessage& m, const TileLists& lists) { send_tile(m, lists, rank); };
    sharing_.receive = [ranks](const auto& where, const auto& got) { receive_tiles(ranks, where, got); };
    // Tiles sent as they are done, from the threads that finish them (one at a time), and received beside rank
    // 0's own: MPI must allow calls from any thread, one at a time.
    sharing_.from_any_thread = provided >= MPI_THREAD_SERIALIZED;
    sharing_.any = [](bool mine) {
      int in = mine ? 1 : 0, out = 0;
      MPI_Allreduce(&in, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
      return out != 0;
    };
    read_share_.index = uint32_t(rank);
    read_share_.count = uint32_t(ranks);
    read_share_.all_sizes = [ranks](uint64_t mine) {
      std::vector<uint64_t> all(size_t(ranks), 0);
      MPI_Allgather(&mine, 1, MPI_UINT64_T, all.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
      return all;
    };
    read_share_.all_bytes = [rank](const char* mine, char* all, const std::vector<uint64_t>& sizes) {
      cdtgpu::all_bytes(mine, all, sizes, rank);
    };
    if (provided >= MPI_THREAD_SERIALIZED) tiles_dir_ = tiles_dir_sharing(rank, ranks, host_, others_done_);
    MPI_Comm here;
    int local = 1;
    if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &here) == MPI_SUCCESS) {
      MPI_Comm_size(here, &local);
      MPI_Comm_free(&here);
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
  if (initialised_) MPI_Finalize();
#endif
}

void MpiSession::abort(int code) const {
#ifdef CDTGPU_MPI
  if (initialised_) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

}  // namespace cdtgpu
