#include "io/mesh_file_ahead.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <span>

#include "io/gis_writers.hpp"

namespace cdtgpu {

namespace {

// PLY's header before the faces exist: a triangulation of V points has at most 2V - 5 triangles (2V - 2 - h,
// h >= 3 of them on the hull), nearly always as many digits as the real count.
uint64_t faces_guess(uint64_t vertices) { return vertices >= 3 ? 2 * vertices - 5 : 0; }

}  // namespace

MeshFileAhead::MeshFileAhead(const std::string& path, const Crs& crs, const WriteOptions& options,
                             const Points& vertices)
    : path_(path), crs_(crs), options_(options), vertices_(vertices.size()) {
  if (!vertices_first(options)) return;
  file_ = ReplacingFile::open(path);
  if (!file_) return;
  head_bytes_ = mesh_head(crs, options, vertices_, faces_guess(vertices_)).size();
  const std::span<const Point3> v(vertices.data(), vertices.size());  // the storage, wherever its owner moves
  written_ = std::async(std::launch::async, [this, v] {
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t end =
        file_->write_at(head_bytes_, [&](std::ostream& out) { write_mesh_vertices(v, options_, out); });
    vertices_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    spdlog::debug("{}: {} vertices written ahead in {:.1f} ms", path_, vertices_, vertices_ms_);
    Points done;  // freed here, on this thread, if its owner has let it go
    {
      std::lock_guard lock(mutex_);
      vertices_done_ = true;
      done = std::move(storage_);
    }
    return end;
  });
}

MeshFileAhead::~MeshFileAhead() { wait(); }  // file_ then goes, uncommitted: removed

void MeshFileAhead::wait() {
  if (written_.valid()) written_.wait();
}

void MeshFileAhead::free_after_writing(Points&& storage) {
  Points now;  // freed at once where the vertices are written already (or were never begun)
  std::lock_guard lock(mutex_);
  if (vertices_done_ || !written_.valid()) now = std::move(storage);
  else storage_ = std::move(storage);
}

bool MeshFileAhead::finish(uint64_t vertices, const TriangleSpans& triangles, bool same_vertices) {
  if (!begun()) return false;
  const uint64_t end = written_.get();  // a failed vertex write throws here
  const std::string head = mesh_head(crs_, options_, vertices, triangles.size());
  if (!same_vertices || vertices != vertices_ || head.size() != head_bytes_) {
    spdlog::debug("{}: the vertices written ahead are not the mesh's; written again", path_);
    file_.reset();
    return false;
  }
  file_->write_at(end, [&](std::ostream& out) { write_mesh_faces(triangles, vertices, options_, out); });
  file_->write_at(0, [&](std::ostream& out) { out << head; });
  file_->commit();
  file_.reset();
  spdlog::debug("{}: finished after the vertices written ahead", path_);
  write_prj_beside(path_, crs_);
  return true;
}

}  // namespace cdtgpu
