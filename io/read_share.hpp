// Reading inputs shared among processes (MPI ranks, issue 29): each process reads a share of every input's
// records and the shares are joined, in order, at the first share (rank 0) into the InputSet one process reading
// everything would have. The other processes send theirs and keep nothing: rank 0 plans the tiles and hands them
// out (core/tile_workers.hpp).
//
//   ReadShare share{rank, ranks, all_sizes, gather_bytes};       // cli/mpi.cpp gives the exchange
//   ReadOptions options;  options.share = &share;
//   read_inputs(specs, options, in);                               // io/input_spec.hpp: the whole at rank 0
//
// XYZ/CSV text is shared by byte ranges cut at line ends, LAS by point records, shapefiles by records. Other
// formats (WKT, GeoJSON, grids, GeoTIFF, stdin) are read whole by one process each, input k by process k % count.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

struct ReadShare {
  uint32_t index = 0, count = 1;  // this process's share, of `count`
  // Every share's number, in share order, at every share; then every share's bytes (sizes as all_sizes gave them)
  // placed one after another at `all` of the first share, in share order (`all` is null at the others).
  std::function<std::vector<uint64_t>(uint64_t mine)> all_sizes;
  std::function<void(const char* mine, char* all, const std::vector<uint64_t>& sizes)> gather_bytes;

  // Items [first, last) of n that this share reads: contiguous, in order, about n / count each.
  std::pair<uint64_t, uint64_t> range(uint64_t n) const {
    return {n * index / count, n * (index + 1) / count};
  }
};

// This share of a text's lines: [begin, end) in bytes, each end just after a '\n' (or the text's end); the
// shares of 0 .. count - 1 cover the text, in order, every line in exactly one.
std::pair<size_t, size_t> share_lines(std::string_view text, const ReadShare& share);

// At the first share: appends every share's `piece` (one input, read by each share into an InputSet of its own) to
// `in`, in share order: points, lines, repairs, LAS point classes; the CRS of the first share that found one, when
// `in` has none. `piece.sources` holds the input's name at its index in `in.sources` on every share. Returns the
// input's LAS point classes, every share's summed. At the others: sends `piece`, leaves `in` as it is and
// returns none.
PointClassCounts join_shares(InputSet& piece, const ReadShare& share, InputSet& in);

}  // namespace cdtgpu
