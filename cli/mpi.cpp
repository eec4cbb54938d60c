#include "cli/mpi.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <cstdlib>
#include <string>

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
// Point to point, in pieces a 32-bit MPI count takes: rank 0 receives every rank's pack in rank order.
std::vector<std::vector<uint32_t>> gather_at_rank0(std::vector<uint32_t> mine, int rank, int ranks) {
  constexpr uint64_t kPiece = uint64_t(1) << 26;
  // Fault injection for the tests: this rank dies before handing over its tiles.
  if (const char* kill = std::getenv("CDTGPU_MPI_TEST_KILL_RANK"); kill && std::atoi(kill) == rank)
    std::raise(SIGKILL);
  if (rank != 0) {
    uint64_t n = mine.size();
    MPI_Send(&n, 1, MPI_UINT64_T, 0, 1, MPI_COMM_WORLD);
    for (uint64_t at = 0; at < n; at += kPiece)
      MPI_Send(mine.data() + at, int(std::min(kPiece, n - at)), MPI_UINT32_T, 0, 2, MPI_COMM_WORLD);
    return {};
  }
  auto all = std::vector<std::vector<uint32_t>>(size_t(ranks));
  all[0] = std::move(mine);
  for (int r = 1; r < ranks; ++r) {
    uint64_t n = 0;
    MPI_Recv(&n, 1, MPI_UINT64_T, r, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    all[size_t(r)].resize(n);
    for (uint64_t at = 0; at < n; at += kPiece)
      MPI_Recv(all[size_t(r)].data() + at, int(std::min(kPiece, n - at)), MPI_UINT32_T, r, 2, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
  }
  return all;
}

// Every rank's bytes to every rank, in rank order: each rank in turn broadcasts its own, in pieces a 32-bit
// MPI count takes.
void all_bytes(const char* mine, char* all, const std::vector<uint64_t>& sizes, int rank) {
  constexpr uint64_t kPiece = uint64_t(1) << 30;
  char* at = all;
  for (size_t r = 0; r < sizes.size(); ++r) {
    if (int(r) == rank && sizes[r]) std::memcpy(at, mine, sizes[r]);
    for (uint64_t done = 0; done < sizes[r]; done += kPiece)
      MPI_Bcast(at + done, int(std::min(kPiece, sizes[r] - done)), MPI_BYTE, int(r), MPI_COMM_WORLD);
    at += sizes[r];
  }
}
#endif

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
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);  // MPI calls come from the main thread only
    initialised_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &sharing_.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &sharing_.ranks);
    const int rank = sharing_.rank, ranks = sharing_.ranks;
    sharing_.gather = [rank, ranks](std::vector<uint32_t> mine) {
      return gather_at_rank0(std::move(mine), rank, ranks);
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
