// Readers hand every polyline to add_polyline, which repairs degenerate geometry and counts what it did.
#pragma once
#include "core/model.hpp"

namespace cdtgpu {

// Throws InputError for non-finite coordinates (naming file and record).
void check_finite(const InputSet& in, uint32_t source, uint64_t record, const Point3& p);

// Appends a point after check_finite.
void add_point(InputSet& in, uint32_t source, uint64_t record, const Point3& p);

// Removes consecutive repeated vertices, drops a ring's repeated closing vertex (and counts a ring given
// without one as closed), keeps a line with a single distinct vertex as a point. Nothing is dropped silently.
void add_polyline(InputSet& in, Polyline line);

}  // namespace cdtgpu
