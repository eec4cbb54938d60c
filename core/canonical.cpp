// canonicalize: one byte-exact order for a mesh, whatever backend or run produced it. Two sorts, O(n log n).
#include "core/canonical.hpp"
#include "core/counting_sort.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>

namespace cdtgpu {

namespace {

bool sorted_and_unique(const Points& v) {
  for (size_t i = 1; i < v.size(); ++i)
    if (v[i - 1].x > v[i].x || (v[i - 1].x == v[i].x && v[i - 1].y >= v[i].y)) return false;
  return true;
}

// Its smallest index first; rotation keeps the orientation.
void rotate_to_smallest(Triangle& t) {
  const int k = int(std::min_element(t.begin(), t.end()) - t.begin());
  t = {t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
}

}  // namespace

void canonicalize_triangles(Triangles& triangles) {
  tbb::parallel_for(size_t(0), triangles.size(), [&](size_t i) { rotate_to_smallest(triangles[i]); });
  const bool sorted = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(1, std::max<size_t>(1, triangles.size()), 1 << 16), true,
      [&](const tbb::blocked_range<size_t>& r, bool ok) {
        for (size_t i = r.begin(); ok && i < r.end(); ++i) ok = !(triangles[i] < triangles[i - 1]);
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  if (!sorted) tbb::parallel_sort(triangles.begin(), triangles.end());
}

void canonicalize_triangles_one_core(Triangles& triangles, size_t vertices) {
  for (Triangle& t : triangles) rotate_to_smallest(t);
  Triangles sorted(triangles.size());
  std::vector<uint32_t> at;
  counting_sort(triangles.data(), triangles.size(), sorted.data(), vertices, [](const Triangle& t) { return t[0]; },
                at);
  // A vertex is the first of a few triangles: each group sorted by its other two.
  for (size_t v = 0; v < vertices; ++v)
    if (at[v + 1] - at[v] > 1) std::sort(sorted.begin() + at[v], sorted.begin() + at[v + 1]);
  triangles = std::move(sorted);
}

void canonicalize(Mesh& mesh) {
  const Points& v = mesh.vertices;
  if (!sorted_and_unique(v)) {  // the backends' vertices usually are: then only the triangles move
    std::vector<uint32_t> order(v.size());
    std::iota(order.begin(), order.end(), 0u);
    // Ties (equal x, y: an invalid mesh) keep their old order, so even then the result is deterministic.
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      if (v[a].x != v[b].x) return v[a].x < v[b].x;
      if (v[a].y != v[b].y) return v[a].y < v[b].y;
      return a < b;
    });
    std::vector<uint32_t> new_index(v.size());
    Points sorted(v.size());
    for (uint32_t i = 0; i < order.size(); ++i) {
      new_index[order[i]] = i;
      sorted[i] = v[order[i]];
    }
    mesh.vertices = std::move(sorted);
    for (Triangle& t : mesh.triangles)
      for (uint32_t& i : t)
        if (i < new_index.size())
          i = new_index[i];  // indices out of range are left as they are: verify reports them
  }
  canonicalize_triangles(mesh.triangles);
}

}  // namespace cdtgpu
