// Several processes through MPI (issue 29): under `mpirun -n R cdtgpu triangulate ...` (or srun) each rank
// reads its share of the inputs and all join them (io/read_share.hpp); every rank prepares the whole input; the
// ranks share the first level's tiles (core/tiles.hpp, TileSharing:
// rank r takes tiles r, r + R, ...), rank 0 gathers their results, merges, and writes the outputs; the files of
// --tiles-out are written by every rank, rank 0 handing each its pieces (io/tiles_dir.hpp).
// Built with MPI when CMake finds it (CDTGPU_MPI); a build without it refuses to run under mpirun instead of
// running R copies of the whole job. A rank that fails ends every rank (MPI_Abort), so no output is written.
//
//   int main(int argc, char** argv) {
//     MpiSession mpi(&argc, &argv);          // MPI_Init only when mpirun / srun started us
//     options.sharing = mpi.sharing();        // null for one process
//     options.input.read.share = mpi.read_share();
//     options.tiles_sharing = mpi.tiles_dir();
//     ...; if (code && mpi.ranks() > 1) mpi.abort(code);
//   }
#pragma once
#include <atomic>
#include <string>

#include "core/tiles.hpp"
#include "io/read_share.hpp"
#include "io/tiles_dir.hpp"

namespace cdtgpu {

class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return sharing_.rank; }
  int ranks() const { return sharing_.ranks; }
  std::string host() const { return host_; }
  // This rank's place among the ranks of its host (the launcher's word), for picking a GPU of its own.
  int local_rank() const { return local_rank_; }
  // The tiles' sharing among the ranks; null for one process.
  const TileSharing* sharing() const { return sharing_.ranks > 1 ? &sharing_ : nullptr; }
  // The inputs' reading shared among the ranks (rank r reads share r, io/read_share.hpp); null for one process.
  const ReadShare* read_share() const { return sharing_.ranks > 1 ? &read_share_ : nullptr; }
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

 private:
  TileSharing sharing_;
  ReadShare read_share_;
  TilesDirSharing tiles_dir_;
  std::atomic<bool> others_done_{false};
  std::string host_, refusal_, cpu_note_;
  int local_rank_ = 0;
  bool initialised_ = false;
};

}  // namespace cdtgpu
