// Several processes through MPI (issue 29): under `mpirun -n R cdtgpu triangulate ...` (or srun) each rank
// reads its share of the inputs and sends it to rank 0, which joins them (io/read_share.hpp), prepares, plans the
// tiles and hands tiles to the other ranks as to devices of its own (core/tile_workers.hpp: a rank gets a tile's
// vertices and segments, answers with its final triangles); rank 0 merges and writes the outputs; the files of
// --tiles-out are written by every rank, rank 0 handing each its pieces (io/tiles_dir.hpp).
// Built with MPI when CMake finds it (CDTGPU_MPI); a build without it refuses to run under mpirun instead of
// running R copies of the whole job. A rank that fails ends every rank (MPI_Abort), so no output is written.
//
//   int main(int argc, char** argv) {
//     MpiSession mpi(&argc, &argv);          // MPI_Init only when mpirun / srun started us
//     options.ranks = mpi.rank_tiles();       // null for one process
//     options.input.read.share = mpi.read_share();
//     options.tiles_sharing = mpi.tiles_dir();
//     ...; if (code && mpi.ranks() > 1) mpi.abort(code);
//   }
#pragma once
#include <atomic>
#include <memory>
#include <string>

#include "core/tile_workers.hpp"
#include "io/read_share.hpp"
#include "io/tiles_dir.hpp"

namespace cdtgpu {

class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return tiles_.rank; }
  int ranks() const { return tiles_.ranks; }
  std::string host() const { return host_; }
  // This rank's place among the ranks of its host (the launcher's word), for picking a GPU of its own.
  int local_rank() const { return local_rank_; }
  int local_ranks() const { return local_ranks_; }  // the ranks of this host, this one included
  // Rank 0's workers, and a worker's side (core/tile_workers.hpp); null for one process.
  const RankTiles* rank_tiles() const { return tiles_.ranks > 1 ? &tiles_ : nullptr; }
  // The inputs' reading shared among the readers (io/read_share.hpp): the first rank of each host, or every rank
  // with CDTGPU_READ_SHARES=ranks. Null for one process, for a rank that reads nothing, and for rank 0 when it is
  // the only reader (it reads the whole input as one process does).
  const ReadShare* read_share() const { return read_share_.count > 1 ? &read_share_ : nullptr; }
  // --tiles-out's files written by every rank (io/tiles_dir.hpp); null for one process, or when the MPI
  // library cannot take calls from the thread that writes the mesh.
  const TilesDirSharing* tiles_dir() const { return tiles_dir_.ranks > 1 ? &tiles_dir_ : nullptr; }
  // Ends every rank with `code` (MPI_Abort): the others may be waiting for this one.
  [[noreturn]] void abort(int code) const;
  // True once no other rank waits for this one (rank 0 has their --tiles-out outcomes): a failure then ends
  // this rank alone, with MPI_Finalize, which mpirun survives better than an abort.
  bool others_done() const { return others_done_; }
  // Why this process cannot run (started by mpirun without MPI in the build); empty when it can.
  std::string refusal() const { return refusal_; }
  // A warning when the launcher bound this rank to far fewer CPUs than its share of the host's (Open MPI
  // binds each rank to one core when -n is 2 or less: every stage then ran 8-15x slower); empty otherwise.
  std::string cpu_note() const { return cpu_note_; }
  double init_ms() const { return init_ms_; }  // MPI_Init_thread's time

 private:
  RankTiles tiles_;
  ReadShare read_share_;
  TilesDirSharing tiles_dir_;
  std::atomic<bool> others_done_{false};
  std::string host_, refusal_, cpu_note_;
  int local_rank_ = 0;
  int local_ranks_ = 1;
  double init_ms_ = 0;
  bool initialised_ = false;
  std::shared_ptr<void> readers_;  // the readers' communicator (cli/mpi.cpp), freed before MPI_Finalize
};

}  // namespace cdtgpu
