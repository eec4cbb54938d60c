// What each input file is for and where its z comes from (cdtgpu triangulate file:role=...,z=...), and which
// part of an InputSet it filled. Parsed in io/input_spec, used by core/drape and core/regions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace cdtgpu {

enum class Role : uint8_t {
  breakline,  // lines and rings are constraints (the default)
  vertices,   // every vertex a loose point, no constraints
  boundary,   // rings bound the domain: triangles outside are dropped (several: union; nesting: regions.hpp)
  hole,       // rings cut the domain: triangles inside are dropped
};
// Boundary and hole inputs: their rings make the regions (core/regions.hpp), which read them again after prepare.
inline bool is_region_role(Role r) { return r == Role::boundary || r == Role::hole; }

// z of an input's vertices beyond what the reader gives (geometry z, or the shapefile field --z-field / z=F).
struct ZRule {
  enum class Kind : uint8_t {
    keep,      // as read
    constant,  // every vertex gets `value`
    drape,     // every vertex gets the z of the surface of the inputs with z, at its (x, y)
    min,       // draped, then each line or ring flattened to the lowest z of its vertices
    mean,      // ... to the mean of its vertices' z
    max,       // ... to the highest
  } kind = Kind::keep;
  double value = 0;  // constant
  bool draped() const {
    return kind == Kind::drape || kind == Kind::min || kind == Kind::mean || kind == Kind::max;
  }
};

// The points [points_begin, points_end) and lines [lines_begin, lines_end) of InputSet that one input added.
struct InputPart {
  size_t points_begin = 0, points_end = 0, lines_begin = 0, lines_end = 0;
  Role role = Role::breakline;
  ZRule z;
  // Every vertex read with a z (LAS points, grid cells): apply_z_rules need not look for missing ones (a pass
  // over 1B LAS points took ~0.16 s on 32 threads).
  bool z_complete = false;
};

}  // namespace cdtgpu
