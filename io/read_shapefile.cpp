// Shapefile reader over shapelib: points and multipoints become vertices, polylines open constraint lines
// (one per part), polygons closed rings (one per part, holes included). z comes from the DBF field named by
// --z-field, else from the geometry (Z types), else 0. The .shp/.shx/.dbf sizes are checked against their
// headers first, so a truncated file is reported as such instead of as a puzzling record. Damage inside the
// file is caught record by record (shapelib reads whatever bytes are there): every record header must agree
// with its .shx entry, every coordinate must be finite and lie in the header's bounding box (and the record's
// own box), and part indices must be in range. A shapefile with 100 bytes flipped used to triangulate without
// a word, with points thousands of kilometres away.
#include <shapefil.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "io/mapped_files.hpp"
#include "io/read_share.hpp"
#include "io/readers.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;

// shapelib reports problems through a hook that prints to stderr by default; keep the text for our message.
thread_local std::string shapelib_error;
void capture_error(const char* message) { shapelib_error = message ? message : "unknown error"; }

// shapelib reads mapped files (or the fuzzer's buffers) through these hooks (io/mapped_files.hpp).
SAHooks capturing_hooks() { return files::hooks(capture_error); }

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
    if (files::is_file(p.string())) return p.string();
  }
  return std::nullopt;
}

// Opens a file the reader needs; InputError when it cannot be read.
files::Open open_file(const std::string& path) {
  files::Open f(files::open(path));
  if (!f) throw InputError(path, 0, "cannot read: " + std::string(std::strerror(errno)));
  return f;
}

uint64_t file_size(const std::string& path) { return open_file(path)->size; }

uint32_t be32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

// Checks the 100-byte header shared by .shp and .shx (file code 9994, big-endian length in 16-bit words)
// against the file's real size.
void check_main_header(const std::string& path) {
  const files::Open f = open_file(path);
  const uint64_t size = f->size;
  unsigned char h[100] = {};
  if (size >= 100) std::memcpy(h, f->data, 100);
  if (size < 100)
    throw InputError(path, 0,
                     "truncated: " + std::to_string(size) + " bytes, shorter than the 100-byte header");
  if (be32(h) != 9994) throw InputError(path, 0, "not a shapefile (bad file code in the header)");
  const uint64_t declared = uint64_t(be32(h + 24)) * 2;
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

// Opens the .dbf and finds the z field. Returns nothing, with the reason in why_not, when the field is
// unavailable and the geometry has its own z (a Z shapefile without the field, such as footprints read along
// with contours: read_inputs decides whether that is allowed); otherwise a missing .dbf or field is an error
// listing what there is.
std::optional<ZField> open_z_field(const std::string& shp, const fs::path& base, const std::string& name,
                                   bool geometry_has_z, int shp_records, std::string& why_not) {
  SAHooks hooks = capturing_hooks();
  const std::optional<std::string> dbf_path = companion(base, ".dbf");
  if (!dbf_path) {
    why_not = "no attribute file " + base.string() + ".dbf, needed for the z field " + name;
    if (geometry_has_z) return std::nullopt;
    throw InputError(shp, 0, why_not);
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
  why_not = "no field " + name + " in " + z.path + " (fields: " + (fields.empty() ? "none" : fields) + ")";
  if (geometry_has_z) return std::nullopt;
  throw InputError(shp, 0, why_not);
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

// The .shx, read directly: (offset, content length) of each record in 16-bit words, which shapelib trusts.
// Each .shp record header (record number, content length) is compared with it, so a damaged offset or length
// is caught instead of read as another record's bytes.
class RecordIndex {
 public:
  RecordIndex(const std::string& shp, const std::string& shx) : shp_path_(shp), shx_path_(shx) {
    const files::Open index_file = open_file(shx);
    const std::string_view bytes = index_file->bytes();
    if (bytes.size() < 100) throw InputError(shx, 0, "truncated");
    index_.assign(bytes.begin() + 100, bytes.end() - std::ptrdiff_t((bytes.size() - 100) % 8));
    shp_.reset(files::open(shp));
    if (!shp_) throw InputError(shp, 0, "cannot open: " + std::string(std::strerror(errno)));
    shp_size_ = shp_->size;
  }
  RecordIndex(const RecordIndex&) = delete;
  RecordIndex& operator=(const RecordIndex&) = delete;
  size_t records() const { return index_.size() / 8; }
  // Record i's bytes in the .shp as the index gives them (header included), unchecked: for splitting work.
  uint64_t bytes(size_t i) const { return length(i) + 8; }

  // Reads only: one index serves every thread.
  void check(int i) const {
    const uint64_t record = uint64_t(i) + 1;
    const uint64_t offset = uint64_t(be32(entry(size_t(i)))) * 2, length = this->length(size_t(i));
    if (offset == 0 && length == 0) return;  // an unused entry, read by shapelib as a NULL shape
    if (offset < 100 || offset + 8 + length > shp_size_)
      throw InputError(shp_path_, record,
                       "corrupt or unreadable record: the index " + shx_path_ + " places it at bytes " +
                           std::to_string(offset) + " to " + std::to_string(offset + 8 + length) +
                           ", outside the file (" + std::to_string(shp_size_) + " bytes)");
    unsigned char h[8] = {};
    const files::File* f = shp_.get();
    if (offset + 8 > f->size) throw InputError(shp_path_, record, "cannot read the record");
    std::memcpy(h, f->data + offset, 8);
    if (be32(h) != record || uint64_t(be32(h + 4)) * 2 != length)
      throw InputError(shp_path_, record,
                       "corrupt record: its header (record " + std::to_string(be32(h)) + ", " +
                           std::to_string(uint64_t(be32(h + 4)) * 2) + " bytes) disagrees with the index " +
                           shx_path_ + " (record " + std::to_string(record) + ", " + std::to_string(length) +
                           " bytes at byte " + std::to_string(offset) + ")");
  }

 private:
  const unsigned char* entry(size_t i) const { return reinterpret_cast<const unsigned char*>(index_.data()) + i * 8; }
  // Record i's content bytes (the index counts 16-bit words).
  uint64_t length(size_t i) const { return uint64_t(be32(entry(i) + 4)) * 2; }
  std::string shp_path_, shx_path_;
  std::string index_;
  uint64_t shp_size_ = 0;
  files::Open shp_;
};

// A box with room for rounding: writers compute it from the same doubles, but some through float or text.
struct Box {
  double min[3], max[3];
  bool valid[3];
  static double slack(double lo, double hi) {
    return 1e-7 * std::max({1.0, std::fabs(lo), std::fabs(hi), hi - lo});
  }
  bool holds(int axis, double v) const {
    if (!valid[axis]) return true;
    const double t = slack(min[axis], max[axis]);
    return v >= min[axis] - t && v <= max[axis] + t;
  }
  std::string text(int axes) const {
    std::string s;
    for (int a = 0; a < axes; ++a)
      s += (a ? " x " : "") + std::string("[") + number_text(min[a]) + ", " + number_text(max[a]) + "]";
    return s;
  }
};

// The header's box: x and y always; z for Z types unless the writer left it at 0 to 0 (some do).
Box header_box(SHPInfo* shp, int type) {
  double lo[4], hi[4];
  SHPGetInfo(shp, nullptr, nullptr, lo, hi);
  Box b{};
  for (int a = 0; a < 3; ++a) {
    b.min[a] = lo[a];
    b.max[a] = hi[a];
    b.valid[a] = std::isfinite(lo[a]) && std::isfinite(hi[a]) && lo[a] <= hi[a];
  }
  if (!has_z(type) || (lo[2] == 0 && hi[2] == 0)) b.valid[2] = false;
  return b;
}

// Every coordinate finite and inside the header's box and, for lines and polygons, the record's own box.
void check_coordinates(const SHPObject& o, const Box& file, bool z_from_geometry, const std::string& path,
                       uint64_t record) {
  Box own{{o.dfXMin, o.dfYMin, o.dfZMin}, {o.dfXMax, o.dfYMax, o.dfZMax}, {true, true, false}};
  own.valid[0] = std::isfinite(o.dfXMin) && std::isfinite(o.dfXMax) && o.dfXMin <= o.dfXMax;
  own.valid[1] = std::isfinite(o.dfYMin) && std::isfinite(o.dfYMax) && o.dfYMin <= o.dfYMax;
  if (is_point_type(o.nSHPType)) own.valid[0] = own.valid[1] = false;  // shapelib derives it from the points
  const int axes = z_from_geometry ? 3 : 2;
  for (int k = 0; k < o.nVertices; ++k) {
    const double v[3] = {o.padfX[k], o.padfY[k], z_from_geometry && o.padfZ ? o.padfZ[k] : 0.0};
    for (int a = 0; a < axes; ++a)
      if (!std::isfinite(v[a])) throw InputError(path, record, "coordinate is not a finite number");
    auto where = [&] {
      std::string s = "vertex " + std::to_string(k + 1) + " (" + number_text(v[0]) + " " + number_text(v[1]);
      if (axes == 3) s += " " + number_text(v[2]);
      return s + ")";
    };
    for (int a = 0; a < axes; ++a) {
      if (!file.holds(a, v[a]))
        throw InputError(path, record,
                         "corrupt record: " + where() +
                             " lies outside the bounding box in the file's header " + file.text(axes));
      if (a < 2 && !own.holds(a, v[a]))
        throw InputError(
            path, record,
            "corrupt record: " + where() + " lies outside the record's bounding box " + own.text(2));
    }
  }
}

// The shapefile's own .prj (path, trimmed text); empty when there is none.
std::pair<std::string, std::string> own_prj(const fs::path& base) {
  const std::optional<std::string> prj = companion(base, ".prj");
  if (!prj) return {};
  const files::Open f(files::open(*prj));
  std::string s = f ? std::string(f->bytes()) : std::string();
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  return {*prj, s};
}

void read_prj(const fs::path& base, InputSet& in) {
  if (!in.source_crs_wkt.empty()) return;
  in.source_crs_wkt = own_prj(base).second;
}

// A .prj of WKT1 GEOGCS / WKT2 GEOGCRS: the coordinates are longitude and latitude in degrees.
bool says_geographic(const std::string& wkt) {
  const std::string w = upper(wkt.substr(0, 8));
  return w.rfind("GEOGCS[", 0) == 0 || w.rfind("GEOGCRS[", 0) == 0;
}

// Under a geographic .prj, a latitude of -95 or a longitude of 200 is damage, not metres.
void check_lon_lat(const SHPObject& o, const std::string& prj, const std::string& path, uint64_t record) {
  for (int k = 0; k < o.nVertices; ++k)
    if (!(o.padfX[k] >= -180 && o.padfX[k] <= 180 && o.padfY[k] >= -90 && o.padfY[k] <= 90))
      throw InputError(
          path, record,
          "vertex " + std::to_string(k + 1) + " (" + number_text(o.padfX[k]) + " " + number_text(o.padfY[k]) +
              ") is not a longitude/latitude, and " + prj +
              " says the coordinates are geographic (longitude -180 to 180, latitude -90 to 90)");
}

}  // namespace

bool shapefile_has_z(const std::string& path) {
  const files::Open f(files::open(path));
  if (!f || f->size < 100) return false;  // the read itself says what is wrong
  unsigned char t[4];
  std::memcpy(t, f->data + 32, 4);  // the shape type, little-endian
  return has_z(int(uint32_t(t[0]) | uint32_t(t[1]) << 8 | uint32_t(t[2]) << 16 | uint32_t(t[3]) << 24));
}

void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in) {
  ZFieldLookup lookup;
  read_shapefile(path, options, in, &lookup);
  if (!options.z_field.empty() && !lookup.found) throw InputError(path, 0, lookup.why_not);
}

void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in, ZFieldLookup* lookup) {
  if (!files::is_file(path)) throw InputError(path, 0, "no such file");
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

  // shapelib counts the records from the .shx header's length, which check_main_header held to the file size.
  RecordIndex index(path, *shx);
  if (index.records() < size_t(count))
    throw InputError(*shx, 0,
                     "truncated: " + std::to_string(index.records()) + " entries for " +
                         std::to_string(count) + " records");
  const Box box = header_box(shp.get(), type);
  // Not a structured binding: lambdas below capture the path, which clang before 16 refuses (the fuzz build).
  const std::pair<std::string, std::string> prj = own_prj(base);
  const std::string& prj_path = prj.first;
  const bool geographic = says_geographic(prj.second);

  std::optional<ZField> z_field;
  if (!options.z_field.empty()) {
    z_field = open_z_field(path, base, options.z_field, has_z(type), count, lookup->why_not);
    lookup->found = z_field.has_value();
  }

  in.sources.push_back(path);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  const size_t before = in.points.size() + in.lines.size();
  // Reads records [begin, end) into part (used by every chunk below).
  auto read_records = [&](int begin, int end, SHPInfo* handle, const RecordIndex& index, const ZField* zf,
                          InputSet& part) {
    for (int i = begin; i < end; ++i) {
      const uint64_t record = uint64_t(i) + 1;
      index.check(i);
      take_error();
      std::unique_ptr<SHPObject, ObjectFree> o(SHPReadObject(handle, i));
      if (!o) {
        const std::string why = take_error();
        throw InputError(path, record, "corrupt or unreadable record" + (why.empty() ? "" : ": " + why));
      }
      if (o->nSHPType == SHPT_NULL) {
        ++part.repairs.null_shapes;
        continue;
      }
      if (o->nSHPType != type)
        throw InputError(path, record,
                         std::string("corrupt record: shape type ") + SHPTypeName(o->nSHPType) +
                             " in a file of " + SHPTypeName(type));
      check_parts(*o, path, record);
      const bool z_from_geometry = !zf && has_z(type) && o->padfZ;
      check_coordinates(*o, box, z_from_geometry, path, record);
      if (geographic) check_lon_lat(*o, prj_path, path, record);
      const double z_attribute = zf ? zf->read(i) : part.nan_for_missing_z ? missing_z() : 0.0;
      auto vertex = [&](int k) {
        return Point3{o->padfX[k], o->padfY[k], z_from_geometry ? o->padfZ[k] : z_attribute};
      };
      if (is_point_type(type)) {
        for (int k = 0; k < o->nVertices; ++k) add_point(part, source, record, vertex(k));
        continue;
      }
      for (int j = 0; j < o->nParts; ++j) {
        const int first = o->panPartStart[j],
                  last = j + 1 < o->nParts ? o->panPartStart[j + 1] : o->nVertices;
        if (first == last) continue;  // an empty part carries nothing
        Polyline line;
        line.points.reserve(size_t(last - first));
        for (int k = first; k < last; ++k) line.points.push_back(vertex(k));
        line.closed = is_polygon_type(type);
        line.source = source;
        line.record = record;
        add_polyline(part, std::move(line));
      }
    }
  };
  // Records are independent: ranges of them are read on all cores into parts appended in record order; the
  // earliest failing record is reported. shapelib's handles are not shared between threads, so each worker
  // thread opens its own once (SHPOpenLL copies the whole .shx into arrays of its own: 2M records took 16 MB
  // a handle, and a handle per range was 64 of them on 16 cores).
  // Chunks of about equal bytes, a few a core, whole records: chunks of 4096 records made a file of 3200 long
  // contours (100M vertices) one chunk, read on one core in 6 s.
  // With a share (io/read_share.hpp): its records only.
  const auto [share_begin, share_end] =
      options.share ? options.share->range(uint64_t(count)) : std::pair<uint64_t, uint64_t>(0, uint64_t(count));
  uint64_t share_bytes = 0;
  for (uint64_t i = share_begin; i < share_end; ++i) share_bytes += index.bytes(i);
  const uint64_t per_chunk =
      std::max<uint64_t>(uint64_t(1) << 18, share_bytes / (4 * std::max(1u, std::thread::hardware_concurrency())) + 1);
  std::vector<Chunk> chunks;
  for (uint64_t first = share_begin, acc = 0, i = share_begin; i < share_end; ++i) {
    acc += index.bytes(i);
    if (acc >= per_chunk || i + 1 == share_end) {
      chunks.push_back({size_t(first), size_t(i + 1), 0});
      first = i + 1, acc = 0;
    }
  }
  std::vector<InputSet> parts(chunks.size());
  struct Handles {
    std::unique_ptr<SHPInfo, ShpClose> shp;
    std::optional<ZField> z;
  };
  tbb::enumerable_thread_specific<Handles> handles;
  parse_chunks(chunks, [&](size_t c, const Chunk& range) {
    InputSet& part = parts[c] = chunk_part(in, source, path);
    Handles& own = handles.local();
    if (!own.shp) {
      SAHooks own_hooks = capturing_hooks();  // SHPOpenLL keeps a copy
      own.shp.reset(SHPOpenLL(path.c_str(), "rb", &own_hooks));
      if (!own.shp) throw InputError(path, uint64_t(range.begin) + 1, "cannot read: " + take_error());
      if (z_field) {
        std::string unused;
        own.z = open_z_field(path, base, options.z_field, has_z(type), count, unused);
      }
    }
    read_records(int(range.begin), int(range.end), own.shp.get(), index, own.z ? &*own.z : nullptr, part);
  });
  append_parts(in, parts);
  read_prj(base, in);
  if (!options.share && in.points.size() + in.lines.size() == before) throw InputError(path, 0, "no geometry");
}

}  // namespace cdtgpu
