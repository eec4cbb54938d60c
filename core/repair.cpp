#include "core/repair.hpp"

#include <cmath>

#include "core/error.hpp"

namespace cdtgpu {

// The file's name is a copy (the conditional makes a std::string of it): made per point, it was a malloc, a
// copy and a free for every vertex read (~15 % of reading a shapefile, perf), so only this rare path makes it.
void check_unusual(const InputSet& in, uint32_t source, uint64_t record, const Point3& p) {
  const bool z_ok = std::isfinite(p.z) || (in.nan_for_missing_z && is_missing_z(p.z));
  const std::string file = source < in.sources.size() ? in.sources[source] : "?";
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
  // The kept vertices compacted in place (a copy of every line was a second allocation and pass).
  Points& kept = line.points;
  size_t k = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    const Point3 p = kept[i];
    check_finite(in, line.source, line.record, p);
    if (k > 0 && kept[k - 1].x == p.x && kept[k - 1].y == p.y) {
      ++in.repairs.repeated_vertices;
      continue;
    }
    kept[k++] = p;
  }
  kept.resize(k);
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
  if (!kept.empty()) in.lines.push_back(std::move(line));
}

}  // namespace cdtgpu
