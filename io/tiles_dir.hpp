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
#include <string>
#include <vector>

#include "core/projection.hpp"
#include "core/tiles.hpp"
#include "io/writers.hpp"

namespace cdtgpu {

// The folder DIR names, without a trailing separator ("out/" -> "out"): what write_tiles_dir puts in place.
std::string tiles_dir_path(const std::string& dir);

// Writes the pieces and the index into a new folder beside DIR, then puts it in DIR's place (the old DIR, if
// any, is removed only then): a failure leaves DIR as it was. DIR must not be a file.
void write_tiles_dir(const std::vector<MeshPiece>& pieces, const Crs& crs, const WriteOptions& options,
                     const std::string& dir);

// The union of the files DIR/index.geojson names: vertices of the same (x, y) merged (their z must agree),
// triangles in canonical order. Throws InputError naming the file for a bad index, a missing or unreadable file,
// counts that differ from the index, or a triangle that is in two files.
Mesh read_tiles_dir(const std::string& dir);

}  // namespace cdtgpu
