#include "core/repair.hpp"

#include <cmath>

#include "core/error.hpp"

namespace cdtgpu {

void check_finite(const InputSet& in, uint32_t source, uint64_t record, const Point3& p) {
  const bool z_ok = std::isfinite(p.z) || (in.nan_for_missing_z && is_missing_z(p.z));
  const std::string& file = source < in.sources.size() ? in.sources[source] : "?";
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !z_ok)
    throw InputError(file, record, "coordinate is not a finite number");
  // Far outside any coordinate reference system (UTM northings reach 1e7, lon/lat 180): a unit or parsing
  // mistake, which would otherwise be triangulated (and passes the predicates' exact range).
  for (const double v : {p.x, p.y})
    if (std::abs(v) > kMaxCoordinate)
      throw InputError(file, record,
                       "coordinate " + number_text(v) + " is beyond ±1e15, far outside any coordinate reference system");
}

void add_point(InputSet& in, uint32_t source, uint64_t record, const Point3& p) {
  check_finite(in, source, record, p);
  in.points.push_back(p);
}

void add_polyline(InputSet& in, Polyline line) {
  Points kept;
  kept.reserve(line.points.size());
  for (const Point3& p : line.points) {
    check_finite(in, line.source, line.record, p);
    if (!kept.empty() && kept.back().x == p.x && kept.back().y == p.y) {
      ++in.repairs.repeated_vertices;
      continue;
    }
    kept.push_back(p);
  }
  if (line.closed) {
    if (kept.size() >= 2 && kept.front().x == kept.back().x && kept.front().y == kept.back().y)
      kept.pop_back();
    else if (kept.size() >= 3)
      ++in.repairs.rings_closed;
  }
  if (kept.size() == 1) {
    ++in.repairs.degenerate_lines;
    in.points.push_back(kept.front());
    return;
  }
  if (kept.size() == 2) line.closed = false;  // a two-vertex "ring" is one segment
  line.points = std::move(kept);
  if (!line.points.empty()) in.lines.push_back(std::move(line));
}

}  // namespace cdtgpu
