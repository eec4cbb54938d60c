// The end-to-end benchmark's input: a "DEM" of uniform points plus contour-like constraint polylines, written
// as the files `cdtgpu triangulate` reads, in several formats so that every kind of reader is timed (and a DEM
// grid over the same square for the .asc and GeoTIFF readers).
//
//   E2eWorkload w = e2e_workload(200000, 50000, 1);       // 200K points, exactly 50K segments, seed 1
//   E2eFiles text = write_e2e_text(w, dir);               // dir/points.xyz + dir/contours.wkt
//   E2eFiles shp = write_e2e_shapefiles(w, dir);          // dir/points.shp + dir/contours.shp (+ .shx, .dbf)
//   // cdtgpu triangulate text.inputs... -o out.ply   (text.bytes: what the reader reads)
//
// Deterministic like core/workloads.hpp: std::mt19937_64 through hand-written mappings, every coordinate an
// integer number of millimetres, so the files and the triangulation are the same on every platform.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "core/raster.hpp"

namespace cdtgpu {

// n points: uniform_points(n, seed) (the 10 km square, x in [500000, 510000), y in [6000000, 6010000), mm).
// m segments as L = ceil(m / k) polylines of k = max(2, round(sqrt(n) / 2)) segments each (the last line gets
// the rest, so the segments total exactly m). A segment is 10 km / (k + 1), about two point spacings.
// Line i lies in its own horizontal band of height H = 10 km / L, [y0 + i*H, y0 + (i+1)*H): it is x-monotone,
// vertex j at x = x0 + 10 km * (j + 0.5) / (k + 1), y = band centre + (u - 0.5) * 0.8 * H, u one draw of a
// stream of its own (seed ^ kE2eStream), x and y rounded to the millimetre; z = 100 + 0.5 * i (its level).
// Bands are disjoint and each line stays in the middle 80% of its band, so lines never cross or touch.
// Sources: "uniform(n=N,seed=S)" and "e2e-contours(m=M,k=K,seed=S)".
struct E2eWorkload {
  InputSet input;
  uint64_t segments = 0;           // m
  uint64_t segments_per_line = 0;  // k
};
E2eWorkload e2e_workload(uint64_t n, uint64_t m, uint64_t seed);

struct E2eFiles {
  std::vector<std::string> inputs;  // what to pass to `cdtgpu triangulate`, points first
  std::vector<std::string> files;   // every file written
  uint64_t bytes = 0;               // the bytes the readers read: .xyz + .wkt, or .shp + .shx (no .dbf: z is
                                    // in the geometry, and the reader opens the .dbf only for --z-field)
};

// points.xyz ("x y z" per line, shortest round-trip text) + contours.wkt (one LINESTRING Z per line).
E2eFiles write_e2e_text(const E2eWorkload& w, const std::string& dir);

// points.shp (PointZ, one record per point) + contours.shp (PolyLineZ, one record per line), each with its
// .shx and a .dbf holding one integer field ID (the 1-based record number), through shapelib.
E2eFiles write_e2e_shapefiles(const E2eWorkload& w, const std::string& dir);

// points.las (LAS 1.4 point format 6, scale 0.001, offset the square's corner: X, Y, Z are the millimetres,
// every point class 2, written by tests/las_writer.hpp) + contours.wkt. The reader's X * scale + offset may
// differ from the text's nearest double by an ulp, so these points are not byte for byte the text's.
E2eFiles write_e2e_las(const E2eWorkload& w, const std::string& dir);

// The grid inputs' DEM: the workload's square as a grid of about n cells of whole metres (cell =
// max(1, round(10 km / sqrt(n))), centres at multiples of it), z a smooth surface in steps of 1/64 m, so the
// values are exact as Float32 and the .asc and the .tif hold the same cells.
Raster e2e_dem(uint64_t n);
// dem.asc (ESRI ASCII) or dem.tif (our GeoTIFF writer: Float32, tiled, DEFLATE) + contours.wkt.
E2eFiles write_e2e_grid(const E2eWorkload& w, const Raster& dem, bool geotiff, const std::string& dir);

}  // namespace cdtgpu
