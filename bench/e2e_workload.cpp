// The end-to-end workload: uniform DEM points + non-crossing contour-like polylines, and their writers (text
// with std::to_chars, shapefiles with shapelib). Cost: O(n + m) to generate and to write.
#include "bench/e2e_workload.hpp"

#include <shapefil.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>

#include "core/repair.hpp"
#include "core/workloads.hpp"
#include "io/geotiff.hpp"
#include "io/gis_writers.hpp"
#include "tests/las_writer.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;

// The contours' own stream, so that changing m does not move the points.
constexpr uint64_t kE2eStream = 0x2545F4914F6CDD1DULL;

std::string path_in(const std::string& dir, const char* name) { return (fs::path(dir) / name).string(); }

// Buffered text output: numbers through std::to_chars (the shortest text that reads back to the same double).
class TextFile {
 public:
  explicit TextFile(std::string path) : path_(std::move(path)), out_(path_, std::ios::binary) {
    if (!out_) throw std::runtime_error("cannot create " + path_);
    buf_.reserve(1 << 20);
  }
  void number(double v) {
    char b[32];
    buf_.append(b, size_t(std::to_chars(b, b + sizeof b, v).ptr - b));
  }
  void text(const char* s) {
    buf_ += s;
    if (buf_.size() > (1 << 20) - 256) flush();
  }
  // "x y z"
  void xyz(const Point3& q) {
    number(q.x);
    text(" ");
    number(q.y);
    text(" ");
    number(q.z);
  }
  void close() {
    flush();
    out_.close();
    if (!out_) throw std::runtime_error("cannot write " + path_);
  }

 private:
  void flush() {
    out_.write(buf_.data(), std::streamsize(buf_.size()));
    buf_.clear();
  }
  std::string path_;
  std::ofstream out_;
  std::string buf_;
};

uint64_t size_of(const std::string& path) { return fs::file_size(path); }

// Files the readers read, all of them: inputs, files and bytes.
E2eFiles inputs_of(std::vector<std::string> paths) {
  E2eFiles files;
  for (const std::string& p : paths) files.bytes += size_of(p);
  files.inputs = std::move(paths);
  files.files = files.inputs;
  return files;
}

// shapelib writes a record with several small seeks, reads and writes (7 system calls per point: 12 s for 1M
// points here); these hooks give it files in memory, read at open and written out at close.
struct MemoryFile {
  std::string path, data;
  size_t pos = 0;
  bool write = false;
};

SAFile memory_open(const char* path, const char* access) {
  auto f = std::make_unique<MemoryFile>();
  f->path = path;
  const std::string mode = access;
  f->write = mode.find_first_of("wa+") != std::string::npos;
  if (mode[0] != 'w') {  // r, r+, rb+, a: start from the file on disk, which must exist
    std::ifstream in(path, std::ios::binary);
    if (!in) return nullptr;
    std::ostringstream text;
    text << in.rdbuf();
    f->data = text.str();
  }
  return reinterpret_cast<SAFile>(f.release());
}
MemoryFile& memory(SAFile file) { return *reinterpret_cast<MemoryFile*>(file); }
SAOffset memory_read(void* p, SAOffset size, SAOffset n, SAFile file) {
  MemoryFile& f = memory(file);
  const size_t items =
      size ? std::min<size_t>(n, (f.data.size() - std::min(f.pos, f.data.size())) / size) : 0;
  std::memcpy(p, f.data.data() + f.pos, items * size);
  f.pos += items * size;
  return items;
}
SAOffset memory_write(void* p, SAOffset size, SAOffset n, SAFile file) {
  MemoryFile& f = memory(file);
  if (f.data.size() < f.pos + size * n) f.data.resize(f.pos + size * n);
  std::memcpy(f.data.data() + f.pos, p, size * n);
  f.pos += size * n;
  return n;
}
SAOffset memory_seek(SAFile file, SAOffset offset, int whence) {
  MemoryFile& f = memory(file);
  f.pos = whence == SEEK_SET ? offset : whence == SEEK_CUR ? f.pos + offset : f.data.size() + offset;
  return 0;
}
SAOffset memory_tell(SAFile file) { return memory(file).pos; }
int memory_flush(SAFile) { return 0; }
int memory_close(SAFile file) {
  std::unique_ptr<MemoryFile> f(&memory(file));
  if (!f->write) return 0;
  std::ofstream out(f->path, std::ios::binary | std::ios::trunc);
  out.write(f->data.data(), std::streamsize(f->data.size()));
  out.close();
  return out ? 0 : -1;
}

SAHooks memory_hooks() {
  SAHooks hooks;
  SASetupDefaultHooks(&hooks);
  hooks.FOpen = memory_open;
  hooks.FRead = memory_read;
  hooks.FWrite = memory_write;
  hooks.FSeek = memory_seek;
  hooks.FTell = memory_tell;
  hooks.FFlush = memory_flush;
  hooks.FClose = memory_close;
  return hooks;
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

// One shapefile (.shp, .shx, .dbf with an integer field ID): `write(shp, dbf)` adds the records.
template <class Write>
void write_shapefile(const std::string& base, int type, Write write, E2eFiles& files) {
  const std::string shp_path = base + ".shp", shx_path = base + ".shx", dbf_path = base + ".dbf";
  {
    SAHooks hooks = memory_hooks();
    std::unique_ptr<SHPInfo, ShpClose> shp(SHPCreateLL(shp_path.c_str(), type, &hooks));
    if (!shp) throw std::runtime_error("shapelib cannot create " + shp_path);
    std::unique_ptr<DBFInfo, DbfClose> dbf(DBFCreateLL(dbf_path.c_str(), "LDID/87", &hooks));
    if (!dbf) throw std::runtime_error("shapelib cannot create " + dbf_path);
    if (DBFAddField(dbf.get(), "ID", FTInteger, 10, 0) < 0)
      throw std::runtime_error("shapelib cannot add the field ID to " + dbf_path);
    auto add = [&](SHPObject* object) {
      std::unique_ptr<SHPObject, ObjectFree> o(object);
      if (!o) throw std::runtime_error("shapelib cannot create a record for " + shp_path);
      const int record = SHPWriteObject(shp.get(), -1, o.get());
      if (record < 0) throw std::runtime_error("shapelib cannot write record to " + shp_path);
      if (!DBFWriteIntegerAttribute(dbf.get(), record, 0, record + 1))
        throw std::runtime_error("shapelib cannot write record to " + dbf_path);
    };
    write(add);
  }
  files.inputs.push_back(shp_path);
  files.files.insert(files.files.end(), {shp_path, shx_path, dbf_path});
  files.bytes += size_of(shp_path) + size_of(shx_path);
}

// contours.wkt: one LINESTRING Z per line.
void write_contours(const E2eWorkload& w, const std::string& wkt) {
  TextFile c(wkt);
  for (const Polyline& line : w.input.lines) {
    c.text("LINESTRING Z (");
    for (size_t j = 0; j < line.points.size(); ++j) {
      if (j) c.text(", ");
      c.xyz(line.points[j]);
    }
    c.text(")\n");
  }
  c.close();
}

}  // namespace

E2eWorkload e2e_workload(uint64_t n, uint64_t m, uint64_t seed) {
  E2eWorkload w;
  w.input = uniform_points(n, seed);
  w.segments = m;
  w.segments_per_line = std::max<uint64_t>(2, uint64_t(std::llround(std::sqrt(double(n)) / 2)));
  const uint64_t k = w.segments_per_line;
  w.input.sources.push_back("e2e-contours(m=" + std::to_string(m) + ",k=" + std::to_string(k) +
                            ",seed=" + std::to_string(seed) + ")");
  const uint32_t source = uint32_t(w.input.sources.size() - 1);
  if (m == 0) return w;
  const uint64_t lines = (m + k - 1) / k;
  // Integer millimetres throughout, divided by 1000 once: the nearest double to the millimetre value.
  const double x0_mm = kUniformX0 * 1000, y0_mm = kUniformY0 * 1000, side_mm = kUniformSide * 1000;
  const double band_mm = side_mm / double(lines);
  std::mt19937_64 rng(seed ^ kE2eStream);
  w.input.lines.reserve(lines);
  for (uint64_t i = 0; i < lines; ++i) {
    const uint64_t segments = i + 1 < lines ? k : m - (lines - 1) * k;
    const double centre_mm = y0_mm + (double(i) + 0.5) * band_mm;
    Polyline line;
    line.source = source;
    line.record = i + 1;
    line.points.reserve(segments + 1);
    for (uint64_t j = 0; j <= segments; ++j) {
      const double x_mm = std::round(x0_mm + side_mm * (double(j) + 0.5) / double(k + 1));
      const double y_mm = std::round(centre_mm + (unit_double(rng) - 0.5) * 0.8 * band_mm);
      line.points.push_back({x_mm / 1000, y_mm / 1000, 100 + 0.5 * double(i)});
    }
    add_polyline(w.input, std::move(line));
  }
  return w;
}

E2eFiles write_e2e_text(const E2eWorkload& w, const std::string& dir) {
  const std::string xyz = path_in(dir, "points.xyz"), wkt = path_in(dir, "contours.wkt");
  TextFile p(xyz);
  for (const Point3& q : w.input.points) {
    p.xyz(q);
    p.text("\n");
  }
  p.close();
  write_contours(w, wkt);
  return inputs_of({xyz, wkt});
}

E2eFiles write_e2e_shapefiles(const E2eWorkload& w, const std::string& dir) {
  E2eFiles files;
  write_shapefile(
      path_in(dir, "points"), SHPT_POINTZ,
      [&](auto add) {
        for (const Point3& q : w.input.points) add(SHPCreateSimpleObject(SHPT_POINTZ, 1, &q.x, &q.y, &q.z));
      },
      files);
  write_shapefile(
      path_in(dir, "contours"), SHPT_ARCZ,
      [&](auto add) {
        std::vector<double> x, y, z;
        for (const Polyline& line : w.input.lines) {
          x.clear(), y.clear(), z.clear();
          for (const Point3& q : line.points) x.push_back(q.x), y.push_back(q.y), z.push_back(q.z);
          add(SHPCreateSimpleObject(SHPT_ARCZ, int(x.size()), x.data(), y.data(), z.data()));
        }
      },
      files);
  return files;
}

E2eFiles write_e2e_las(const E2eWorkload& w, const std::string& dir) {
  const std::string las = path_in(dir, "points.las"), wkt = path_in(dir, "contours.wkt");
  test::LasFile f;
  f.format = 6;
  f.minor = 4;
  f.scale[0] = f.scale[1] = f.scale[2] = 0.001;
  f.offset[0] = kUniformX0, f.offset[1] = kUniformY0, f.offset[2] = 0;
  f.points.resize(w.input.points.size());
  for (size_t i = 0; i < w.input.points.size(); ++i) {
    const Point3& p = w.input.points[i];
    f.points[i] = {.X = int32_t(std::llround((p.x - kUniformX0) * 1000)),
                   .Y = int32_t(std::llround((p.y - kUniformY0) * 1000)),
                   .Z = int32_t(std::llround(p.z * 1000)),
                   .cls = 2};
  }
  {
    std::ofstream out(las, std::ios::binary);
    out << test::las_bytes(f);
    if (!out.flush()) throw std::runtime_error("cannot write " + las);
  }
  write_contours(w, wkt);
  return inputs_of({las, wkt});
}

Raster e2e_dem(uint64_t n) {
  Raster r;
  GridSpec& g = r.spec;
  g.cell = std::max(1.0, std::round(kUniformSide / std::sqrt(double(std::max<uint64_t>(n, 1)))));
  g.ix0 = int64_t(std::ceil(kUniformX0 / g.cell));
  g.iy0 = int64_t(std::ceil(kUniformY0 / g.cell));
  g.ncols = g.nrows = uint64_t(kUniformSide / g.cell);
  r.z.resize(g.ncols * g.nrows);
  for (uint64_t row = 0; row < g.nrows; ++row)
    for (uint64_t col = 0; col < g.ncols; ++col) {
      const double x = g.x(col) - kUniformX0, y = g.y(row) - kUniformY0;
      r.z[row * g.ncols + col] =
          100 + std::round(64 * (40 * std::sin(x / 1500) * std::cos(y / 1700) + 0.002 * (x + y))) / 64;
    }
  return r;
}

E2eFiles write_e2e_grid(const E2eWorkload& w, const Raster& dem, bool geotiff, const std::string& dir) {
  const std::string grid = path_in(dir, geotiff ? "dem.tif" : "dem.asc"), wkt = path_in(dir, "contours.wkt");
  if (geotiff)
    write_geotiff_grid_file(dem, Crs{}, grid);
  else
    write_ascii_grid_file(dem, Crs{}, grid);
  write_contours(w, wkt);
  return inputs_of({grid, wkt});
}

}  // namespace cdtgpu
