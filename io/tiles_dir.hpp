// `--tiles-out DIR`: a mesh as one file per tile plus DIR/index.geojson, and the union read back for verify.
//
//   std::vector<MeshPiece> pieces = split_mesh(mesh, 1'000'000);     // core/tiles.hpp
//   write_tiles_dir(pieces, crs, write_options, "out/");             // out/tile_0001.ply ..., out/index.geojson
//   Mesh whole = read_tiles_dir("out/");                              // the union, canonical
//
// index.geojson: a FeatureCollection, one Polygon feature per tile (its vertices' extent) with the properties
// file (relative to DIR), tile (1-based), vertices and triangles. A triangle is in the file of the tile holding
// its smallest vertex; vertices shared between tiles are repeated in each file that uses them.
#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/projection.hpp"
#include "core/tiles.hpp"
#include "io/writers.hpp"

namespace cdtgpu {

// The folder DIR names, without a trailing separator ("out/" -> "out"): what write_tiles_dir puts in place.
std::string tiles_dir_path(const std::string& dir);

// The folder written by several processes (MPI ranks, cli/mpi.cpp): process r writes the files of pieces
// r, r + R, r + 2R, ...; process 0 makes the pieces, writes the index and puts the folder in place once every
// process says its files are written.
struct TilesDirSharing {
  int rank = 0, ranks = 1;
  // Process 0: hands process r the new folder's path, the mesh's CRS and its pieces (index t, the piece).
  std::function<void(int rank, const std::string& fresh, const Crs& crs,
                     const std::vector<std::pair<size_t, const MeshPiece*>>&)>
      send;
  // Other processes: what process 0 handed them.
  struct Handed {
    std::string fresh;
    Crs crs;
    std::vector<std::pair<size_t, MeshPiece>> pieces;
  };
  std::function<Handed()> receive;
  // Every process's outcome (empty: its files are written; else why not, naming the process), gathered at
  // process 0 in process order; the others get an empty list.
  std::function<std::vector<std::string>(const std::string& mine)> outcomes;
};

// Writes the pieces and the index into a new folder beside DIR, then puts it in DIR's place (the old DIR, if
// any, is removed only then): a failure leaves DIR as it was. DIR must not be a file. With `sharing`, process 0
// calls this with every piece and the others call write_shared_tiles.
void write_tiles_dir(const std::vector<MeshPiece>& pieces, const Crs& crs, const WriteOptions& options,
                     const std::string& dir, const TilesDirSharing* sharing = nullptr);
// A process other than 0: writes the pieces process 0 hands it and reports how that went.
void write_shared_tiles(const WriteOptions& options, const TilesDirSharing& sharing);

// The union of the files DIR/index.geojson names: vertices of the same (x, y) merged (their z must agree),
// triangles in canonical order. Throws InputError naming the file for a bad index, a missing or unreadable file,
// counts that differ from the index, or a triangle that is in two files.
Mesh read_tiles_dir(const std::string& dir);

}  // namespace cdtgpu
