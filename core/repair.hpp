// Readers hand every polyline to add_polyline, which repairs degenerate geometry and counts what it did.
#pragma once
#include <cfloat>
#include <cmath>

#include "core/model.hpp"

namespace cdtgpu {

// The largest |x| or |y| accepted from a reader.
constexpr double kMaxCoordinate = 1e15;

// Throws InputError naming the source and record for a NaN or infinite coordinate (a z read as missing is fine)
// and for an x or y beyond ±kMaxCoordinate. Inline: every point of every reader passes here, and a plain one
// takes three comparisons (NaN fails |v| <= kMaxCoordinate too).
void check_unusual(const InputSet& in, uint32_t source, uint64_t record, const Point3& p);
inline void check_finite(const InputSet& in, uint32_t source, uint64_t record, const Point3& p) {
  if (!(std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate && std::abs(p.z) <= DBL_MAX))
    check_unusual(in, source, record, p);
}

// Appends a point after check_finite.
void add_point(InputSet& in, uint32_t source, uint64_t record, const Point3& p);

// Removes consecutive repeated vertices, drops a ring's repeated closing vertex (and counts a ring given
// without one as closed), keeps a line with a single distinct vertex as a point. Nothing is dropped silently.
void add_polyline(InputSet& in, Polyline line);

}  // namespace cdtgpu
