// TIN writers. Coordinates are written with the shortest text that reads back to the same double.
#pragma once
#include <ostream>
#include <span>
#include <string>

#include "core/model.hpp"
#include "core/triangle_spans.hpp"
#include "core/projection.hpp"

namespace cdtgpu {

enum class MeshFormat { Obj, Ply, Wkt, LandXml, Sms2dm };  // LandXml, Sms2dm: io/mesh_formats.hpp

struct WriteOptions {
  MeshFormat format = MeshFormat::Ply;
  bool ascii = false;           // PLY only; OBJ and WKT are text
  bool wkt_multipolygon = false;  // WKT: MULTIPOLYGON Z instead of TIN Z
};

// From the extension (.obj, .ply, .wkt, .xml (LandXML), .2dm); throws UsageError for anything else.
MeshFormat format_from_extension(const std::string& path);
MeshFormat parse_format(const std::string& name);  // "obj", "ply", "wkt", "landxml", "2dm"
const char* mesh_extension(MeshFormat format);      // ".obj", ".ply", ".wkt", ".xml", ".2dm"

// Records the CRS where the format allows: OBJ a comment line, PLY a comment, WKT nothing in the stream
// (a .prj beside the file, written by write_mesh_file).
void write_mesh(const Mesh& mesh, const Crs& crs, const WriteOptions& options, std::ostream& out);

// Writes to path through a temporary file in the same folder and renames it, so a failed run leaves no
// half-written file; "-" writes to stdout. Also writes path's .prj when the CRS has a WKT.
void write_mesh_file(const Mesh& mesh, const Crs& crs, const WriteOptions& options, const std::string& path);
// The same, OBJ or PLY only (vertices_first), the triangles read where they lie (a tiled run's, left in its
// tiles' runs: CdtResult::in_runs).
void write_mesh_file(const Points& vertices, const TriangleSpans& triangles, const Crs& crs,
                     const WriteOptions& options, const std::string& path);

// OBJ and PLY files in their three parts, for a file begun before its triangles exist (io/mesh_file_ahead):
// the text before the vertices (PLY's header, which names both counts), the vertices, the faces. write_mesh
// writes the same bytes in one go. vertices_first: false for WKT, LandXML and 2DM.
bool vertices_first(const WriteOptions& options);
std::string mesh_head(const Crs& crs, const WriteOptions& options, uint64_t vertices, uint64_t triangles);
void write_mesh_vertices(std::span<const Point3> vertices, const WriteOptions& options, std::ostream& out);
void write_mesh_faces(const Mesh& mesh, const WriteOptions& options, std::ostream& out);
void write_mesh_faces(const TriangleSpans& triangles, uint64_t vertices, const WriteOptions& options,
                      std::ostream& out);

// Reads a mesh written by write_mesh (OBJ, PLY ascii/binary, WKT TIN Z / MULTIPOLYGON Z) for verify.
Mesh read_mesh_file(const std::string& path);

}  // namespace cdtgpu
