// The canonical order that makes output bytes the same on every run and every backend.
#pragma once
#include "core/model.hpp"

namespace cdtgpu {

// Vertices sorted by (x, y) (triangle indices remapped); each triangle rotated so its smallest index comes
// first, orientation kept; triangles sorted lexicographically.
void canonicalize(Mesh& mesh);

}  // namespace cdtgpu
