// TIN writers. Coordinates are written with the shortest text that reads back to the same double.
#pragma once
#include <ostream>
#include <string>

#include "core/model.hpp"
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

// Reads a mesh written by write_mesh (OBJ, PLY ascii/binary, WKT TIN Z / MULTIPOLYGON Z) for verify.
Mesh read_mesh_file(const std::string& path);

}  // namespace cdtgpu
