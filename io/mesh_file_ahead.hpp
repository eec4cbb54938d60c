// A mesh file begun before its triangles exist. An OBJ or PLY file holds every vertex before any face, and a run
// that neither adds vertices (crossings) nor drops them (regions) outputs the prepared ones: their section is
// written on a thread of its own while the triangulation runs, and the faces follow once they are made (PLY's
// header, which names the face count, is written last, over room left for it).
//
//   MeshFileAhead ahead(path, crs, options, prepared.vertices);  // writing from their storage
//   ...                                                            // ahead.wait() before it is freed
//   if (!ahead.finish(mesh.vertices.size(), TriangleSpans(mesh.triangles), mesh_has_the_prepared_vertices))
//     write_mesh_file(mesh, crs, options, path);
#pragma once
#include <cstdint>
#include <future>
#include <memory>
#include <mutex>
#include <string>

#include "core/model.hpp"
#include "core/projection.hpp"
#include "io/atomic_file.hpp"
#include "io/writers.hpp"

namespace cdtgpu {

class MeshFileAhead {
 public:
  // Begins nothing (begun() false) where the file cannot be written in parts: formats other than OBJ and PLY,
  // stdout, and what write_file_atomically writes in place (devices, FIFOs).
  MeshFileAhead(const std::string& path, const Crs& crs, const WriteOptions& options, const Points& vertices);
  ~MeshFileAhead();  // unfinished: the thread waited for, the temporary file removed
  bool begun() const { return file_ != nullptr; }
  double vertices_ms() const { return vertices_ms_; }  // the vertex section's write (its own thread), once done

  // The vertices' storage is read no more: it may be freed (moving its owner is fine before).
  void wait();
  // The vertices' storage, freed once they are written (on the writing thread) instead of waited for.
  void free_after_writing(Points&& storage);

  // Adds the faces of `triangles` and renames the file into place (with its .prj) when `same_vertices` (the
  // caller's word that the mesh's `vertices` are the ones begun with), their count agrees, and PLY's header has the length
  // that was left for it (the face count was guessed). Otherwise removes the temporary file and returns false:
  // the caller writes the whole file. A failed write throws as write_mesh_file does.
  bool finish(uint64_t vertices, const TriangleSpans& triangles, bool same_vertices);

 private:
  std::string path_;
  Crs crs_;
  WriteOptions options_;
  uint64_t vertices_ = 0;
  size_t head_bytes_ = 0;
  double vertices_ms_ = 0;
  std::unique_ptr<ReplacingFile> file_;
  std::mutex mutex_;
  bool vertices_done_ = false;
  Points storage_;                 // free_after_writing's, until then
  std::future<uint64_t> written_;  // the vertex section's end; last: waited for before the rest goes
};

}  // namespace cdtgpu
