// Test helper: the bundled Katoomba sample (contours with z from ELEV, DEM points, building footprints),
// projected as `--crs auto` does and triangulated by the CGAL backend: the README command's mesh, before
// regions (the sample has none). Built once per test executable.
#pragma once
#include <string>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/projection.hpp"
#include "io/readers.hpp"

namespace cdtgpu::test {

inline InputSet katoomba_input() {
  InputSet in;
  ReadOptions ro;
  ro.z_field = "ELEV";
  const std::string dir = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  read_inputs({dir + "contours.shp", dir + "dem.xyz", dir + "buildings.shp"}, ro, in);
  project(in, choose_crs(in, parse_crs("auto")));
  return in;
}

inline const Mesh& katoomba_mesh() {
  static const Mesh mesh = triangulate_cgal(prepare(katoomba_input())).mesh;
  return mesh;
}

}  // namespace cdtgpu::test
