// Text of many items (vertices, faces, grid rows) formatted on all cores and written in order.
//
//   write_items(out, mesh.vertices.size(), 80, [&](uint64_t v, char* p) {
//     p = put_shortest(p, mesh.vertices[v].x);  ...;  *p++ = '\n';  return p;
//   });
//
// Blocks of items are formatted into buffers of their own on all cores and written in their order as they
// come (a TBB pipeline), so the bytes are those of one thread formatting them, and formatting overlaps the
// writing; the blocks in flight (a few per core, about 1 MiB each) bound the memory.
#pragma once
#include <tbb/blocked_range.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <ostream>
#include <stdexcept>
#include <string_view>

#include "core/triangle_spans.hpp"
#include "io/mesh_formats.hpp"

namespace cdtgpu {

// format_block(first, count, p) writes items [first, first + count)'s text at p (room for max_chars each) and
// returns its end: for items read in runs (a mesh's faces from core/triangle_spans).
template <class FormatBlock>
void write_blocks(std::ostream& out, uint64_t n, size_t max_chars, FormatBlock&& format_block) {
  struct Block {
    uint64_t first = 0, count = 0;
    std::unique_ptr<char[]> text;
    size_t size = 0;
  };
  const uint64_t per_block = std::max<uint64_t>(1, (uint64_t(1) << 20) / std::max<size_t>(1, max_chars));
  uint64_t next = 0;
  tbb::parallel_pipeline(
      size_t(4 * tbb::this_task_arena::max_concurrency()),
      tbb::make_filter<void, Block*>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& fc) -> Block* {
                                       if (next >= n) {
                                         fc.stop();
                                         return nullptr;
                                       }
                                       auto* b = new Block{next, std::min(per_block, n - next), {}, 0};
                                       next += b->count;
                                       return b;
                                     }) &
          tbb::make_filter<Block*, Block*>(tbb::filter_mode::parallel,
                                           [&](Block* b) {
                                             b->text.reset(new char[b->count * max_chars]);
                                             char* p = format_block(b->first, b->count, b->text.get());
                                             b->size = size_t(p - b->text.get());
                                             return b;
                                           }) &
          tbb::make_filter<Block*, void>(tbb::filter_mode::serial_in_order, [&](Block* b) {
            std::unique_ptr<Block> own(b);
            if (out) out.write(b->text.get(), std::streamsize(b->size));
          }));
  if (!out) throw std::runtime_error("write failed");
}

// format(i, p) writes item i's text at p (room for max_chars) and returns its end.
template <class Format>
void write_items(std::ostream& out, uint64_t n, size_t max_chars, Format&& format) {
  write_blocks(out, n, max_chars, [&](uint64_t first, uint64_t count, char* p) {
    for (uint64_t i = first; i < first + count; ++i) p = format(i, p);
    return p;
  });
}

inline char* put(char* p, std::string_view s) {
  std::memcpy(p, s.data(), s.size());
  return p + s.size();
}
// The shortest text that reads back to v, as std::to_chars chooses it (at most 24 characters).
inline char* put_shortest(char* p, double v) { return std::to_chars(p, p + 32, v).ptr; }
inline char* put_uint(char* p, uint64_t v) { return std::to_chars(p, p + 24, v).ptr; }
// "x y z", each the shortest text (at most 3 * 25 characters).
inline char* put_xyz(char* p, const Point3& q) {
  p = put_shortest(p, q.x);
  *p++ = ' ';
  p = put_shortest(p, q.y);
  *p++ = ' ';
  return put_shortest(p, q.z);
}
// " a b c": the triangle's vertex indices plus `base` (0 or 1), each after a space (at most 3 * 11 characters).
inline char* put_indices(char* p, const Triangle& tri, uint64_t base) {
  for (uint32_t v : tri) {
    *p++ = ' ';
    p = put_uint(p, v + base);
  }
  return p;
}

// Every triangle's indices checked on all cores before any is written; the first bad one throws
// checked_triangle's message.
inline void check_triangles(const TriangleSpans& triangles, uint64_t vertices) {
  const size_t n = triangles.size();
  auto valid = [&](size_t first, size_t count) {
    bool ok = true;
    triangles.each(first, count, [&](std::span<const Triangle> s) {
      for (const Triangle& t : s) ok = ok && t[0] < vertices && t[1] < vertices && t[2] < vertices;
    });
    return ok;
  };
  const bool all = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 1 << 16), true,
      [&](const tbb::blocked_range<size_t>& r, bool ok) { return ok && valid(r.begin(), r.size()); },
      [](bool a, bool b) { return a && b; });
  if (all) return;
  size_t t = 0;
  triangles.each(0, n, [&](std::span<const Triangle> s) {
    for (const Triangle& tri : s) checked_triangle(tri, t++, vertices);
  });
}
inline void check_triangles(const Mesh& mesh) {
  check_triangles(TriangleSpans(mesh.triangles), mesh.vertices.size());
}

}  // namespace cdtgpu
