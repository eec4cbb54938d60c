// A shaded-relief picture of a DEM grid (core/raster.hpp) for a quick look: Horn's slope, light from the
// north-west at 45 degrees, tinted by elevation; NODATA cells transparent.
// Usage:
//   Raster dem = rasterise(mesh, preview_cell(mesh, 1000));   // about 1000 cells on the long side
//   std::vector<uint8_t> rgba = hillshade_rgba(dem);           // nrows x ncols x 4, row 0 north
//   draw_edges(rgba, dem.spec, prepared.vertices, prepared.constraints);   // the constraint lines on top
//   write_png_file("tin.png", dem.spec.ncols, dem.spec.nrows, rgba);   // io/write_png.hpp
#pragma once
#include <cstdint>
#include <vector>

#include "core/raster.hpp"

namespace cdtgpu {

// The cell size that puts about `pixels` cell centres on the mesh's longer side.
double preview_cell(const Mesh& mesh, uint32_t pixels);

// Shade in [0, 1] of each cell (Lambert, light at azimuth 315 and altitude 45 degrees; slopes from Horn's
// 3 x 3 differences; a neighbour off the grid or NODATA is the opposite one mirrored through the centre, so a
// plane is shaded evenly up to its edges); NODATA cells get -1.
std::vector<float> hillshade(const Raster& dem);

// RGBA bytes, row 0 north: elevation tint (green, brown, white from low to high) times 0.3 + 0.7 * shade.
std::vector<uint8_t> hillshade_rgba(const Raster& dem);

// Draws each edge (a, b) of `vertices` as a one-pixel dark line onto an image of dem's grid (pixel = cell);
// parts outside the grid are clipped.
void draw_edges(std::vector<uint8_t>& rgba, const GridSpec& grid, const Points& vertices,
                const std::vector<Edge>& edges);

}  // namespace cdtgpu
