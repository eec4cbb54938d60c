// The triangulation as it lives on the GPU between passes: the Delaunay passes (gpu/delaunay.cpp) build it, the
// constraint passes edit it in place, download_triangles() brings the finite triangles back in canonical order.
//
// Slots hold a closed triangulation of the sphere: the finite triangles plus one infinite triangle per convex
// hull edge, whose third vertex is the symbolic INF_VERTEX (no coordinates, so exactness never depends on a
// huge "far" point). Layout in shaders/layout.h:
//   verts[3t+k]  vertex k of slot t, counter-clockwise (INF_VERTEX may sit at any k);
//   nbrs[3t+k]   NBR(u, k'): slot u is across the edge opposite vertex k, and that edge is opposite k' in u.
// The finite triangle (a, b, c) has the infinite triangle (b, a, INF) across its hull edge a-b.
// Points are (x, y) doubles in canonical order (sorted by x, then y, unique): a vertex id is its index.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/model.hpp"
#include "gpu/buffers.hpp"
#include "gpu/context.hpp"

namespace cdtgpu::gpu {

struct GpuTriangulation {
  Buffer points;    // double x, y per vertex
  Buffer verts;     // uint per corner, 3 per slot
  Buffer nbrs;      // uint per edge, 3 per slot
  uint32_t num_points = 0;
  uint32_t num_slots = 0;  // slots in use (finite and infinite triangles)
  uint32_t capacity = 0;   // slots allocated
  // Optional, uint per vertex: a slot holding it (any one), as the Delaunay build leaves it; the constraint
  // inserter starts its walks there instead of computing its own vertex map, and keeps it up to date.
  Buffer vertex_slots;
};

// Host copy of the raw slots, for tests and for building a triangulation on the CPU.
struct HostTriangulation {
  std::vector<double> xy;  // 2 per vertex
  std::vector<uint32_t> verts, nbrs;
};

// Adds the infinite triangles and the adjacency to a set of finite CCW triangles that triangulate the convex
// hull of the points (e.g. CGAL's). Throws std::invalid_argument if an edge has more than two triangles.
HostTriangulation make_host_triangulation(std::span<const double> xy, std::span<const Triangle> finite);

GpuTriangulation upload_triangulation(const Context& ctx, const HostTriangulation& host, uint32_t capacity = 0);
HostTriangulation download_host(const Context& ctx, const GpuTriangulation& tri);

// Finite triangles, each rotated to start at its smallest index, sorted: core's canonical order.
Triangles finite_triangles(const HostTriangulation& host);
Triangles download_triangles(const Context& ctx, const GpuTriangulation& tri);

// Empty when the slots are a valid closed triangulation: neighbours symmetric, shared edges with matching
// vertices in opposite directions, finite triangles strictly CCW (exact orient2d), every vertex used;
// otherwise the first problems found, one per line.
std::string check_triangulation(const HostTriangulation& host);

}  // namespace cdtgpu::gpu
