#include "gpu/triangulation.hpp"

#include <algorithm>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "core/predicates.hpp"
#include "shaders/layout.h"

namespace cdtgpu::gpu {

using namespace layout;

namespace {

uint64_t edge_key(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

}  // namespace

HostTriangulation make_host_triangulation(std::span<const double> xy, std::span<const Triangle> finite) {
  HostTriangulation h;
  h.xy.assign(xy.begin(), xy.end());
  for (const Triangle& t : finite) h.verts.insert(h.verts.end(), t.begin(), t.end());
  // Directed edge a->b of slot t, edge k (opposite vertex k) -> NBR(t, k).
  std::unordered_map<uint64_t, uint32_t> directed;
  directed.reserve(finite.size() * 3);
  auto add_edges = [&](uint32_t t) {
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t a = h.verts[3 * t + (k + 1) % 3], b = h.verts[3 * t + (k + 2) % 3];
      if (!directed.emplace(edge_key(a, b), NBR(t, k)).second)
        throw std::invalid_argument("edge used twice in the same direction");
    }
  };
  for (uint32_t t = 0; t < finite.size(); ++t) add_edges(t);
  // Hull edges: a->b with no b->a. Their infinite triangle is (b, a, INF).
  std::vector<std::array<uint32_t, 2>> hull;
  for (auto& [key, code] : directed)
    if (!directed.count(edge_key(uint32_t(key), uint32_t(key >> 32)))) hull.push_back({uint32_t(key >> 32), uint32_t(key)});
  std::sort(hull.begin(), hull.end());
  for (auto& [a, b] : hull) {
    uint32_t t = uint32_t(h.verts.size() / 3);
    h.verts.insert(h.verts.end(), {b, a, INF_VERTEX});
    add_edges(t);
  }
  h.nbrs.assign(h.verts.size(), NO_TRI);
  for (uint32_t t = 0; t < h.verts.size() / 3; ++t)
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t a = h.verts[3 * t + (k + 1) % 3], b = h.verts[3 * t + (k + 2) % 3];
      auto it = directed.find(edge_key(b, a));
      if (it == directed.end()) throw std::invalid_argument("open edge: the triangles do not close up");
      h.nbrs[3 * t + k] = it->second;
    }
  return h;
}

GpuTriangulation upload_triangulation(const Context& ctx, const HostTriangulation& host, uint32_t capacity) {
  GpuTriangulation g;
  g.num_points = uint32_t(host.xy.size() / 2);
  g.num_slots = uint32_t(host.verts.size() / 3);
  g.capacity = std::max(capacity, g.num_slots);
  g.points = upload_new(ctx, host.xy, "points");
  g.verts = create_addressed_buffer(ctx, uint64_t(g.capacity) * 3 * sizeof(uint32_t), "tri_verts");
  g.nbrs = create_addressed_buffer(ctx, uint64_t(g.capacity) * 3 * sizeof(uint32_t), "tri_nbrs");
  if (g.num_slots) {
    upload(ctx, g.verts, host.verts.data(), host.verts.size() * sizeof(uint32_t));
    upload(ctx, g.nbrs, host.nbrs.data(), host.nbrs.size() * sizeof(uint32_t));
  }
  return g;
}

HostTriangulation download_host(const Context& ctx, const GpuTriangulation& tri) {
  HostTriangulation h;
  h.xy = download_vector<double>(ctx, tri.points, size_t(tri.num_points) * 2);
  h.verts = download_vector<uint32_t>(ctx, tri.verts, size_t(tri.num_slots) * 3);
  h.nbrs = download_vector<uint32_t>(ctx, tri.nbrs, size_t(tri.num_slots) * 3);
  return h;
}

Triangles finite_triangles(const HostTriangulation& host) {
  Triangles out;
  out.reserve(host.verts.size() / 6 + 1);
  for (size_t t = 0; t < host.verts.size() / 3; ++t) {
    Triangle v{host.verts[3 * t], host.verts[3 * t + 1], host.verts[3 * t + 2]};
    if (v[0] == INF_VERTEX || v[1] == INF_VERTEX || v[2] == INF_VERTEX) continue;
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Triangles download_triangles(const Context& ctx, const GpuTriangulation& tri) {
  HostTriangulation h;
  h.verts = download_vector<uint32_t>(ctx, tri.verts, size_t(tri.num_slots) * 3);
  return finite_triangles(h);
}

std::string check_triangulation(const HostTriangulation& h) {
  std::ostringstream problems;
  int count = 0;
  auto report = [&](const std::string& what) {
    if (count++ < 10) problems << what << '\n';
  };
  const size_t slots = h.verts.size() / 3, points = h.xy.size() / 2;
  auto xy = [&](uint32_t i) { return pred::XY{h.xy[2 * i], h.xy[2 * i + 1]}; };
  std::vector<char> used(points, 0);
  for (size_t t = 0; t < slots; ++t) {
    const uint32_t* v = &h.verts[3 * t];
    int inf = 0;
    for (int k = 0; k < 3; ++k) {
      if (v[k] == INF_VERTEX) {
        ++inf;
        continue;
      }
      if (v[k] >= points) {
        report("slot " + std::to_string(t) + ": vertex " + std::to_string(v[k]) + " out of range");
        continue;
      }
      used[v[k]] = 1;
    }
    if (inf > 1) report("slot " + std::to_string(t) + ": two infinite vertices");
    if (inf == 0 && v[0] < points && v[1] < points && v[2] < points &&
        pred::orient2d(xy(v[0]), xy(v[1]), xy(v[2])) <= 0)
      report("slot " + std::to_string(t) + ": finite triangle not strictly counter-clockwise");
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t code = h.nbrs[3 * t + k], u = NBR_TRI(code), j = NBR_EDGE(code);
      if (u >= slots || j > 2) {
        report("slot " + std::to_string(t) + " edge " + std::to_string(k) + ": neighbour out of range");
        continue;
      }
      if (h.nbrs[3 * u + j] != NBR(uint32_t(t), k))
        report("slot " + std::to_string(t) + " edge " + std::to_string(k) + ": neighbour does not point back");
      uint32_t a = v[(k + 1) % 3], b = v[(k + 2) % 3];
      uint32_t c = h.verts[3 * u + (j + 1) % 3], d = h.verts[3 * u + (j + 2) % 3];
      if (a != d || b != c)
        report("slot " + std::to_string(t) + " edge " + std::to_string(k) + ": shared edge vertices differ");
    }
  }
  for (size_t p = 0; p < points; ++p)
    if (!used[p]) {
      report("vertex " + std::to_string(p) + " is in no triangle");
      break;
    }
  if (count > 10) problems << "... " << count - 10 << " more\n";
  return problems.str();
}

}  // namespace cdtgpu::gpu
