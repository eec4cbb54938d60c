// z for inputs that have none: draped on the surface of the inputs that do, a constant, or flattened.
//
//   std::vector<InputPart> parts = read_inputs(specs, defaults, in);   // io/input_spec.hpp
//   project(in, crs);
//   DrapeStats s = apply_z_rules(in, parts);   // before prepare(in)
//
// The surface is the CDT (triangulate_cgal) of every input whose z is its own (rule keep: geometry z or a
// field), its constraints included; inputs given a constant, and vertices read without z, are not part of it.
// A draped vertex gets the linear interpolation of the triangle containing it (on an edge or a vertex: the
// lowest-numbered triangle containing it, which gives the same z up to rounding). Containment is decided with
// exact orientation tests. A vertex outside the surface's hull gets the z of the nearest point of the hull
// (linear along that edge).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/input_parts.hpp"
#include "core/model.hpp"

namespace cdtgpu {

struct DrapeStats {
  uint64_t draped_vertices = 0;    // input vertices whose z came from the surface
  uint64_t outside_surface = 0;    // of those, vertices beyond the surface's hull
  uint64_t constant_vertices = 0;  // input vertices given a constant z
  // Per part: vertices read without z (missing_z(), see InputSet::nan_for_missing_z) in parts whose rule is
  // keep; they get z = 0 as before and are not part of the drape surface.
  std::vector<uint64_t> zero_z;
};

// Applies each part's z rule to its points and lines; afterwards no z is missing_z(). Throws UsageError when
// something is to be draped and the inputs with z do not make a surface (fewer than 3 points, or all on a
// line).
DrapeStats apply_z_rules(InputSet& in, const std::vector<InputPart>& parts);

// The surface itself, for tests: z at (x, y) on `surface` (a CDT, canonical), as apply_z_rules computes it.
class DrapeSurface {
 public:
  explicit DrapeSurface(Mesh surface);
  double z_at(double x, double y, bool* outside = nullptr) const;

 private:
  Mesh mesh_;
  double x0_ = 0, y0_ = 0, cell_w_ = 1, cell_h_ = 1;
  uint32_t nx_ = 1, ny_ = 1;
  std::vector<uint32_t> first_, cells_;        // CSR: triangles whose bounding box meets each cell
  std::vector<std::array<uint32_t, 2>> hull_;  // hull edges (vertex indices)
  uint32_t cell_x(double x) const;
  uint32_t cell_y(double y) const;
};

}  // namespace cdtgpu
