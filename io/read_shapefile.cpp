// Shapefile reader over shapelib: points and multipoints become vertices, polylines open constraint lines
// (one per part), polygons closed rings (one per part, holes included). z comes from the DBF field named by
// --z-field, else from the geometry (Z types), else 0. The .shp/.shx/.dbf sizes are checked against their
// headers first, so a truncated file is reported as such instead of as a puzzling record.
#include <shapefil.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "io/readers.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;

// shapelib reports problems through a hook that prints to stderr by default; keep the text for our message.
thread_local std::string shapelib_error;
void capture_error(const char* message) { shapelib_error = message ? message : "unknown error"; }

SAHooks capturing_hooks() {
  SAHooks hooks;
  SASetupDefaultHooks(&hooks);
  hooks.Error = capture_error;
  return hooks;
}

std::string take_error() {
  std::string s = std::move(shapelib_error);
  shapelib_error.clear();
  return s;
}

struct ShpClose {
  void operator()(SHPInfo* h) const { SHPClose(h); }
};
struct DbfClose {
  void operator()(DBFInfo* h) const { DBFClose(h); }
};
struct ObjectFree {
  void operator()(SHPObject* o) const { SHPDestroyObject(o); }
};

std::string upper(std::string s) {
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// The companion file base+ext, in lower or upper case (files from Windows tools often use .SHX, .DBF).
std::optional<std::string> companion(const fs::path& base, const std::string& ext) {
  for (const std::string& e : {ext, upper(ext)}) {
    fs::path p = base;
    p += e;
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return std::nullopt;
}

uint64_t file_size(const std::string& path) {
  std::error_code ec;
  const uintmax_t n = fs::file_size(path, ec);
  if (ec) throw InputError(path, 0, "cannot read: " + ec.message());
  return n;
}

// Checks the 100-byte header shared by .shp and .shx (file code 9994, big-endian length in 16-bit words)
// against the file's real size.
void check_main_header(const std::string& path) {
  const uint64_t size = file_size(path);
  unsigned char h[100] = {};
  std::ifstream f(path, std::ios::binary);
  if (size < 100 || !f.read(reinterpret_cast<char*>(h), 100))
    throw InputError(path, 0,
                     "truncated: " + std::to_string(size) + " bytes, shorter than the 100-byte header");
  auto be32 = [&](int at) {
    return uint32_t(h[at]) << 24 | uint32_t(h[at + 1]) << 16 | uint32_t(h[at + 2]) << 8 | h[at + 3];
  };
  if (be32(0) != 9994) throw InputError(path, 0, "not a shapefile (bad file code in the header)");
  const uint64_t declared = uint64_t(be32(24)) * 2;
  if (size < declared)
    throw InputError(path, 0,
                     "truncated: the header gives " + std::to_string(declared) + " bytes, the file has " +
                         std::to_string(size));
}

bool has_z(int type) {
  return type == SHPT_POINTZ || type == SHPT_ARCZ || type == SHPT_POLYGONZ || type == SHPT_MULTIPOINTZ;
}
bool is_point_type(int type) {
  return type == SHPT_POINT || type == SHPT_POINTZ || type == SHPT_POINTM || type == SHPT_MULTIPOINT ||
         type == SHPT_MULTIPOINTZ || type == SHPT_MULTIPOINTM;
}
bool is_line_type(int type) { return type == SHPT_ARC || type == SHPT_ARCZ || type == SHPT_ARCM; }
bool is_polygon_type(int type) {
  return type == SHPT_POLYGON || type == SHPT_POLYGONZ || type == SHPT_POLYGONM;
}

// The attribute table, opened only when --z-field asks for it.
struct ZField {
  std::unique_ptr<DBFInfo, DbfClose> dbf;
  std::string path;
  int field = -1;

  double read(int record) const {
    shapelib_error.clear();
    if (DBFIsAttributeNULL(dbf.get(), record, field))
      throw InputError(path, uint64_t(record) + 1, "z field is empty (NULL)");
    const char* text = DBFReadStringAttribute(dbf.get(), record, field);
    if (!text || !shapelib_error.empty())
      throw InputError(path, uint64_t(record) + 1, "cannot read the record: " + take_error());
    // Parsed here rather than with DBFReadDoubleAttribute, whose atof turns garbage into 0 without a word.
    std::string_view s(text);
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double v = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size())
      throw InputError(path, uint64_t(record) + 1, "z field is not a number: '" + std::string(text) + "'");
    return v;
  }
};

// Opens the .dbf and finds the z field. Returns nothing when the field is unavailable and the geometry has
// its own z (a Z shapefile without the field, such as footprints read along with contours); otherwise a
// missing .dbf or field is an error listing what there is.
std::optional<ZField> open_z_field(const std::string& shp, const fs::path& base, const std::string& name,
                                   bool geometry_has_z, int shp_records) {
  SAHooks hooks = capturing_hooks();
  const std::optional<std::string> dbf_path = companion(base, ".dbf");
  if (!dbf_path) {
    if (geometry_has_z) return std::nullopt;
    throw InputError(shp, 0, "no attribute file " + base.string() + ".dbf, needed for the z field " + name);
  }
  ZField z;
  z.path = *dbf_path;
  take_error();
  z.dbf.reset(DBFOpenLL(dbf_path->c_str(), "rb", &hooks));
  if (!z.dbf) {
    const std::string why = take_error();
    throw InputError(z.path, 0,
                     "cannot read the attribute table: " + (why.empty() ? "not a valid .dbf file" : why));
  }
  const DBFInfo& d = *z.dbf;
  const uint64_t need = uint64_t(d.nHeaderLength) + uint64_t(d.nRecords) * uint64_t(d.nRecordLength);
  if (d.nRecords < 0 || d.nRecordLength <= 0 || file_size(z.path) < need)
    throw InputError(z.path, 0,
                     "truncated or corrupt: the header gives " + std::to_string(d.nRecords) + " records of " +
                         std::to_string(d.nRecordLength) + " bytes (" + std::to_string(need) +
                         " bytes), the file has " + std::to_string(file_size(z.path)));
  if (d.nRecords < shp_records)
    throw InputError(
        z.path, 0,
        "has " + std::to_string(d.nRecords) + " records, the .shp has " + std::to_string(shp_records));
  std::string fields;
  const int n = DBFGetFieldCount(z.dbf.get());
  for (int i = 0; i < n; ++i) {
    char field_name[XBASE_FLDNAME_LEN_READ + 1] = {};
    const DBFFieldType type = DBFGetFieldInfo(z.dbf.get(), i, field_name, nullptr, nullptr);
    fields += (i ? ", " : "") + std::string(field_name);
    if (upper(field_name) != upper(name)) continue;
    if (type != FTInteger && type != FTDouble)
      throw InputError(z.path, 0, "z field " + std::string(field_name) + " is not numeric");
    z.field = i;
  }
  if (z.field >= 0) return z;
  if (geometry_has_z) return std::nullopt;
  throw InputError(
      shp, 0, "no field " + name + " in " + z.path + " (fields: " + (fields.empty() ? "none" : fields) + ")");
}

void check_parts(const SHPObject& o, const std::string& path, uint64_t record) {
  if (o.nVertices < 0 || o.nParts < 0 || (o.nVertices > 0 && (!o.padfX || !o.padfY)))
    throw InputError(path, record, "corrupt record: bad vertex or part count");
  if (is_point_type(o.nSHPType)) return;
  if (o.nVertices > 0 && (o.nParts == 0 || !o.panPartStart || o.panPartStart[0] != 0))
    throw InputError(path, record, "corrupt record: parts do not start at the first vertex");
  for (int j = 0; j < o.nParts; ++j) {
    const int next = j + 1 < o.nParts ? o.panPartStart[j + 1] : o.nVertices;
    if (o.panPartStart[j] < 0 || o.panPartStart[j] > next || next > o.nVertices)
      throw InputError(path, record,
                       "corrupt record: part " + std::to_string(j + 1) + " has a bad vertex range");
  }
}

void read_prj(const fs::path& base, InputSet& in) {
  if (!in.source_crs_wkt.empty()) return;
  const std::optional<std::string> prj = companion(base, ".prj");
  if (!prj) return;
  std::ifstream f(*prj, std::ios::binary);
  std::ostringstream text;
  text << f.rdbuf();
  std::string s = text.str();
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  in.source_crs_wkt = s;
}

}  // namespace

void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "no such file");
  const fs::path base = fs::path(path).replace_extension();
  const std::optional<std::string> shx = companion(base, ".shx");
  if (!shx) throw InputError(path, 0, "no index file " + base.string() + ".shx (a shapefile needs its .shx)");
  check_main_header(path);
  check_main_header(*shx);

  SAHooks hooks = capturing_hooks();
  take_error();
  std::unique_ptr<SHPInfo, ShpClose> shp(SHPOpenLL(path.c_str(), "rb", &hooks));
  if (!shp) throw InputError(path, 0, "cannot read: " + take_error());
  int count = 0, type = 0;
  SHPGetInfo(shp.get(), &count, &type, nullptr, nullptr);
  if (!is_point_type(type) && !is_line_type(type) && !is_polygon_type(type) &&
      !(type == SHPT_NULL && count == 0))
    throw InputError(path, 0, std::string("shape type ") + SHPTypeName(type) + " is not supported");

  std::optional<ZField> z_field;
  if (!options.z_field.empty()) z_field = open_z_field(path, base, options.z_field, has_z(type), count);

  in.sources.push_back(path);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  const size_t before = in.points.size() + in.lines.size();
  for (int i = 0; i < count; ++i) {
    const uint64_t record = uint64_t(i) + 1;
    take_error();
    std::unique_ptr<SHPObject, ObjectFree> o(SHPReadObject(shp.get(), i));
    if (!o) {
      const std::string why = take_error();
      throw InputError(path, record, "corrupt or unreadable record" + (why.empty() ? "" : ": " + why));
    }
    if (o->nSHPType == SHPT_NULL) {
      ++in.repairs.null_shapes;
      continue;
    }
    if (o->nSHPType != type)
      throw InputError(path, record,
                       std::string("corrupt record: shape type ") + SHPTypeName(o->nSHPType) +
                           " in a file of " + SHPTypeName(type));
    check_parts(*o, path, record);
    const bool z_from_geometry = !z_field && has_z(type) && o->padfZ;
    const double z_attribute = z_field ? z_field->read(i) : in.nan_for_missing_z ? missing_z() : 0.0;
    auto vertex = [&](int k) {
      return Point3{o->padfX[k], o->padfY[k], z_from_geometry ? o->padfZ[k] : z_attribute};
    };
    if (is_point_type(type)) {
      for (int k = 0; k < o->nVertices; ++k) add_point(in, source, record, vertex(k));
      continue;
    }
    for (int j = 0; j < o->nParts; ++j) {
      const int first = o->panPartStart[j], last = j + 1 < o->nParts ? o->panPartStart[j + 1] : o->nVertices;
      if (first == last) continue;  // an empty part carries nothing
      Polyline line;
      line.points.reserve(size_t(last - first));
      for (int k = first; k < last; ++k) line.points.push_back(vertex(k));
      line.closed = is_polygon_type(type);
      line.source = source;
      line.record = record;
      add_polyline(in, std::move(line));
    }
  }
  read_prj(base, in);
  if (in.points.size() + in.lines.size() == before) throw InputError(path, 0, "no geometry");
}

}  // namespace cdtgpu
