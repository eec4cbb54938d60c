// TIN writers for OBJ, PLY (binary little-endian or ascii) and WKT (TIN Z or MULTIPOLYGON Z). Text is built in a
// large buffer with std::to_chars (shortest text that reads back to the same double), never with iostream
// formatting, so millions of triangles are written at buffer speed. Triangle indices are checked as they are
// written: a bad mesh throws part way, and write_mesh_file then leaves no file behind.
#include "io/writers.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_group.h>

#include <spdlog/spdlog.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <span>
#include <utility>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"
#include "core/uninit.hpp"
#include "io/atomic_file.hpp"
#include "io/gis_writers.hpp"
#include "io/mesh_formats.hpp"
#include "io/parallel_text.hpp"

namespace cdtgpu {

namespace {

static_assert(std::endian::native == std::endian::little, "the binary PLY writer assumes a little-endian host");

// An output buffer flushed to the stream in large blocks.
class Sink {
 public:
  explicit Sink(std::ostream& out) : out_(out), buf_(1 << 20) {}
  ~Sink() = default;

  void flush() {
    out_.write(buf_.data(), std::streamsize(n_));
    n_ = 0;
    if (!out_) throw std::runtime_error("write failed");
  }
  void reserve(size_t k) {
    if (n_ + k > buf_.size()) flush();
  }
  void text(const char* s, size_t len) {
    if (len == 0) return;  // s may be null then (an empty array's data()), which memcpy must not get
    if (len > buf_.size()) {
      flush();
      out_.write(s, std::streamsize(len));
      if (!out_) throw std::runtime_error("write failed");
      return;
    }
    reserve(len);
    std::memcpy(buf_.data() + n_, s, len);
    n_ += len;
  }
  void text(const std::string& s) { text(s.data(), s.size()); }
  void ch(char c) {
    reserve(1);
    buf_[n_++] = c;
  }

 private:
  std::ostream& out_;
  std::vector<char> buf_;
  size_t n_ = 0;
};

// One line: a name with a line break inside would break the header or comment.
std::string one_line(const std::string& s) {
  std::string r = s;
  std::replace_if(r.begin(), r.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
  return r;
}

// OBJ and PLY put every vertex before any face: their parts (writers.hpp) are written one after another here,
// or apart by io/mesh_file_ahead.
std::string obj_head(const Crs& crs) { return crs.name.empty() ? "" : "# crs: " + one_line(crs.name) + "\n"; }

std::string ply_head(const Crs& crs, bool ascii, uint64_t vertices, uint64_t triangles) {
  std::string h = "ply\nformat ";
  h += ascii ? "ascii" : "binary_little_endian";
  h += " 1.0\n";
  if (!crs.name.empty()) h += "comment crs " + one_line(crs.name) + "\n";
  h += "element vertex " + std::to_string(vertices) +
       "\nproperty double x\nproperty double y\nproperty double z\n"
       "element face " +
       std::to_string(triangles) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  return h;
}

}  // namespace

void write_mesh_vertices(std::span<const Point3> vertices, const WriteOptions& options, std::ostream& out) {
  if (options.format == MeshFormat::Obj)
    return write_items(out, vertices.size(), 3 * 25 + 3,
                       [&](uint64_t v, char* p) { return put(put_xyz(put(p, "v "), vertices[v]), "\n"); });
  if (options.ascii)
    return write_items(out, vertices.size(), 3 * 25 + 3,
                       [&](uint64_t v, char* p) { return put(put_xyz(p, vertices[v]), "\n"); });
  // Point3 is three packed doubles, the vertex element's layout: the array goes out as it is.
  static_assert(sizeof(Point3) == 3 * sizeof(double));
  out.write(reinterpret_cast<const char*>(vertices.data()), std::streamsize(vertices.size() * sizeof(Point3)));
}

void write_mesh_faces(const TriangleSpans& triangles, uint64_t vertices, const WriteOptions& options,
                      std::ostream& out) {
  check_triangles(triangles, vertices);
  const size_t n = triangles.size();
  if (options.format == MeshFormat::Obj || options.ascii) {
    const bool obj = options.format == MeshFormat::Obj;
    return write_blocks(out, n, 3 * 11 + 2, [&](uint64_t first, uint64_t count, char* p) {
      triangles.each(first, count, [&](std::span<const Triangle> s) {
        for (const Triangle& t : s)
          p = obj ? put(put_indices(put(p, "f"), t, 1), "\n")   // OBJ counts from 1
                  : put(put_indices(put(p, "3"), t, 0), "\n");
      });
      return p;
    });
  }
  // Faces are 13 bytes each (a count byte and three indices), packed on all cores in blocks of 4 MiB reused (a
  // 65 MB array for 5M faces cost more in page faults than its packing), the next block packed while this thread
  // writes the last.
  const auto t0 = std::chrono::steady_clock::now();
  constexpr size_t kFacesPerBlock = (size_t(4) << 20) / 13;
  std::vector<char> packed(std::min(n, kFacesPerBlock) * 13), next(packed.size());
  auto pack = [&](size_t first, std::vector<char>& to) {
    const size_t count = std::min(kFacesPerBlock, n - first);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 4096), [&](const tbb::blocked_range<size_t>& r) {
      char* f = to.data() + r.begin() * 13;
      triangles.each(first + r.begin(), r.size(), [&](std::span<const Triangle> s) {
        for (const Triangle& t : s) {
          f[0] = 3;
          std::memcpy(f + 1, t.data(), 12);
          f += 13;
        }
      });
    });
  };
  if (n) pack(0, packed);
  for (size_t first = 0; first < n; first += kFacesPerBlock) {
    const size_t after = first + kFacesPerBlock;
    tbb::task_group packing;
    if (after < n) packing.run([&] { pack(after, next); });
    try {
      out.write(packed.data(), std::streamsize(std::min(kFacesPerBlock, n - first) * 13));
    } catch (...) {
      packing.wait();
      throw;
    }
    packing.wait();
    packed.swap(next);
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  spdlog::debug("faces: {} packed and written in {:.0f} ms ({:.1f} GB/s)", n, ms, n * 13 / 1e6 / std::max(ms, 1e-3));
}

void write_mesh_faces(const Mesh& mesh, const WriteOptions& options, std::ostream& out) {
  write_mesh_faces(TriangleSpans(mesh.triangles), mesh.vertices.size(), options, out);
}

namespace {

void write_wkt(const Mesh& mesh, bool multipolygon, Sink& out, std::ostream& stream) {
  out.text(multipolygon ? "MULTIPOLYGON Z " : "TIN Z ");
  if (mesh.triangles.empty()) {
    out.text("EMPTY\n", 6);
    return;
  }
  check_triangles(mesh);
  // Each vertex appears in about six triangles, four times in each ring list: formatted once, on all cores
  // (blocks of vertices into texts of their own, then one pool).
  const size_t V = mesh.vertices.size();
  constexpr size_t kBlock = 1 << 14;
  const size_t blocks = (V + kBlock - 1) / kBlock;
  std::vector<std::string> block_text(blocks);
  std::vector<uint8_t> length(V);
  tbb::parallel_for(size_t(0), blocks, [&](size_t k) {
    char buf[80];
    for (size_t v = k * kBlock; v < std::min(V, (k + 1) * kBlock); ++v) {
      char* e = put_xyz(buf, mesh.vertices[v]);
      length[v] = uint8_t(e - buf);
      block_text[k].append(buf, e);
    }
  });
  std::vector<size_t> start(V + 1, 0);
  for (size_t v = 0; v < V; ++v) start[v + 1] = start[v] + length[v];
  std::string pool;
  pool.reserve(start[V]);
  for (const std::string& b : block_text) pool += b;
  free_storage(block_text);
  auto point = [&](char* p, uint32_t v) { return put(p, std::string_view(pool).substr(start[v], length[v])); };
  out.ch('(');
  out.flush();
  write_items(stream, mesh.triangles.size(), 4 * 80 + 12, [&](uint64_t t, char* p) {
    const Triangle& tri = mesh.triangles[t];
    p = put(p, t ? ", ((" : "((");
    p = point(p, tri[0]);
    p = put(p, ", ");
    p = point(p, tri[1]);
    p = put(p, ", ");
    p = point(p, tri[2]);
    p = put(p, ", ");
    p = point(p, tri[0]);  // rings repeat their first point
    return put(p, "))");
  });
  out.text(")\n", 2);
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Each format's file extension, both ways.
constexpr std::pair<MeshFormat, const char*> kExtensions[] = {{MeshFormat::Obj, ".obj"},
                                                              {MeshFormat::Ply, ".ply"},
                                                              {MeshFormat::Wkt, ".wkt"},
                                                              {MeshFormat::LandXml, ".xml"},
                                                              {MeshFormat::Sms2dm, ".2dm"}};

}  // namespace

const char* mesh_extension(MeshFormat format) {
  for (const auto& [f, e] : kExtensions)
    if (f == format) return e;
  return ".ply";
}

MeshFormat format_from_extension(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  for (const auto& [format, e] : kExtensions)
    if (ext == e) return format;
  throw UsageError("cannot tell the output format of '" + path + "' from its extension '" + ext +
                   "' (use .obj, .ply, .wkt, .xml or .2dm, or --format)");
}

MeshFormat parse_format(const std::string& name) {
  const std::string n = lower(name);
  if (n == "obj") return MeshFormat::Obj;
  if (n == "ply") return MeshFormat::Ply;
  if (n == "wkt") return MeshFormat::Wkt;
  if (n == "landxml" || n == "xml") return MeshFormat::LandXml;
  if (n == "2dm") return MeshFormat::Sms2dm;
  throw UsageError("unknown output format '" + name + "' (use obj, ply, wkt, landxml or 2dm)");
}

bool vertices_first(const WriteOptions& options) {
  return options.format == MeshFormat::Obj || options.format == MeshFormat::Ply;
}

std::string mesh_head(const Crs& crs, const WriteOptions& options, uint64_t vertices, uint64_t triangles) {
  return options.format == MeshFormat::Obj ? obj_head(crs) : ply_head(crs, options.ascii, vertices, triangles);
}

namespace {

// OBJ and PLY: their three parts in one go.
void write_vertices_first(const Points& vertices, const TriangleSpans& triangles, const Crs& crs,
                          const WriteOptions& options, std::ostream& out) {
  out << mesh_head(crs, options, vertices.size(), triangles.size());
  write_mesh_vertices({vertices.data(), vertices.size()}, options, out);
  write_mesh_faces(triangles, vertices.size(), options, out);
}

}  // namespace

void write_mesh(const Mesh& mesh, const Crs& crs, const WriteOptions& options, std::ostream& out) {
  if (vertices_first(options))
    return write_vertices_first(mesh.vertices, TriangleSpans(mesh.triangles), crs, options, out);
  Sink sink(out);
  switch (options.format) {
    case MeshFormat::Obj:
    case MeshFormat::Ply: break;
    case MeshFormat::Wkt: write_wkt(mesh, options.wkt_multipolygon, sink, out); break;
    case MeshFormat::LandXml: write_landxml(mesh, crs, output_timestamp(), out); return;
    case MeshFormat::Sms2dm: write_2dm(mesh, crs, out); return;
  }
  sink.flush();
}

void write_prj_beside(const std::string& path, const Crs& crs) {
  if (path == "-" || crs.wkt.empty()) return;
  const std::string prj = std::filesystem::path(path).replace_extension(".prj").string();
  write_file_atomically(prj, [&](std::ostream& out) { out << crs.wkt; });
}

void write_mesh_file(const Mesh& mesh, const Crs& crs, const WriteOptions& options, const std::string& path) {
  write_file_atomically(path, [&](std::ostream& out) { write_mesh(mesh, crs, options, out); });
  write_prj_beside(path, crs);
}

void write_mesh_file(const Points& vertices, const TriangleSpans& triangles, const Crs& crs,
                     const WriteOptions& options, const std::string& path) {
  if (!vertices_first(options))
    throw std::logic_error("write_mesh_file: triangles in spans are written as OBJ or PLY only");
  write_file_atomically(path, [&](std::ostream& out) { write_vertices_first(vertices, triangles, crs, options, out); });
  write_prj_beside(path, crs);
}

}  // namespace cdtgpu
