// canonicalize: one byte-exact order for a mesh, whatever backend or run produced it. Two sorts, O(n log n).
#include "core/canonical.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace cdtgpu {

namespace {

bool sorted_and_unique(const std::vector<Point3>& v) {
  for (size_t i = 1; i < v.size(); ++i)
    if (v[i - 1].x > v[i].x || (v[i - 1].x == v[i].x && v[i - 1].y >= v[i].y)) return false;
  return true;
}

}  // namespace

void canonicalize(Mesh& mesh) {
  const std::vector<Point3>& v = mesh.vertices;
  if (sorted_and_unique(v)) {  // the backends' vertices usually are: only the triangles move
    tbb::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t i) {
      Triangle& t = mesh.triangles[i];
      const int k = int(std::min_element(t.begin(), t.end()) - t.begin());
      t = {t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
    });
    tbb::parallel_sort(mesh.triangles.begin(), mesh.triangles.end());
    return;
  }
  std::vector<uint32_t> order(v.size());
  std::iota(order.begin(), order.end(), 0u);
  // Ties (equal x, y: an invalid mesh) keep their old order, so even then the result is deterministic.
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    if (v[a].x != v[b].x) return v[a].x < v[b].x;
    if (v[a].y != v[b].y) return v[a].y < v[b].y;
    return a < b;
  });
  std::vector<uint32_t> new_index(v.size());
  std::vector<Point3> sorted(v.size());
  for (uint32_t i = 0; i < order.size(); ++i) {
    new_index[order[i]] = i;
    sorted[i] = v[order[i]];
  }
  mesh.vertices = std::move(sorted);

  for (Triangle& t : mesh.triangles) {
    // Indices out of range are left as they are: verify reports them.
    Triangle r = t;
    for (uint32_t& i : r)
      if (i < new_index.size()) i = new_index[i];
    // Rotation keeps the orientation.
    const int k = int(std::min_element(r.begin(), r.end()) - r.begin());
    t = {r[k], r[(k + 1) % 3], r[(k + 2) % 3]};
  }
  std::sort(mesh.triangles.begin(), mesh.triangles.end());
}

}  // namespace cdtgpu
