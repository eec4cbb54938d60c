// Reads a TIN back for verify: OBJ, PLY (ascii, binary little- or big-endian) and WKT (TIN Z, MULTIPOLYGON Z,
// POLYHEDRALSURFACE Z). Numbers are parsed with std::from_chars, which is exact.
//
// Own readers rather than CGAL's read_OBJ / read_PLY (CGAL 5.5): those return only true/false (no line or
// element to report), reject a mesh with no faces (which the writers produce validly), and read_OBJ accepts a
// face index one past the last vertex (its bound check is off by one) and non-triangular faces silently.
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "io/mesh_formats.hpp"
#include "io/writers.hpp"

namespace cdtgpu {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A cursor over one line of text.
struct Tokens {
  std::string_view s;
  size_t i = 0;
  void skip() {
    while (i < s.size() && is_space(s[i])) ++i;
  }
  bool done() {
    skip();
    return i >= s.size();
  }
  std::string_view next() {
    skip();
    const size_t b = i;
    while (i < s.size() && !is_space(s[i])) ++i;
    return s.substr(b, i - b);
  }
};

bool parse_double(std::string_view t, double& v) {
  if (t.empty()) return false;
  // from_chars does not take a leading '+'.
  if (t[0] == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return ec == std::errc() && p == t.data() + t.size() && std::isfinite(v);
}

template <class Int>
bool parse_int(std::string_view t, Int& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return ec == std::errc() && p == t.data() + t.size() && !t.empty();
}

std::string shown(std::string_view t) { return "'" + std::string(t.substr(0, 40)) + "'"; }

std::string slurp(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open");
  std::string data;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) data.reserve(size);
  data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path, 0, "read error");
  return data;
}

// Splits text into lines, calling f(line, line_number) for each; '\r' before '\n' is white space.
template <class F>
void for_lines(std::string_view text, F&& f, size_t& pos, uint64_t& line_no) {
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    ++line_no;
    const std::string_view line = text.substr(pos, end - pos);
    pos = std::min(end + 1, text.size());  // a last line without '\n' ends at the end, not past it
    if (!f(line, line_no)) return;
  }
}

// ---- OBJ ----

Mesh read_obj(const std::string& path, std::string_view text) {
  Mesh m;
  struct Pending {
    size_t triangle;
    uint64_t line;
  };
  std::vector<Pending> forward;  // faces naming vertices not yet seen: checked at the end
  size_t pos = 0;
  uint64_t line_no = 0;
  for_lines(
      text,
      [&](std::string_view line, uint64_t ln) {
        Tokens tk{line};
        if (tk.done()) return true;
        const std::string_view key = tk.next();
        if (key[0] == '#') return true;
        if (key == "v") {
          Point3 p;
          double* c[3] = {&p.x, &p.y, &p.z};
          for (double* d : c) {
            const std::string_view t = tk.next();
            if (!parse_double(t, *d))
              throw InputError(path, ln, t.empty() ? "vertex needs x y z" : "bad coordinate " + shown(t));
          }
          m.vertices.push_back(p);
          return true;
        }
        if (key == "f") {
          Triangle tri{};
          int n = 0;
          bool pending = false;
          while (!tk.done()) {
            std::string_view t = tk.next();
            t = t.substr(0, t.find('/'));  // "v/vt/vn": keep the vertex
            int64_t i = 0;
            if (!parse_int(t, i) || i == 0) throw InputError(path, ln, "bad face index " + shown(t));
            if (i < 0) i += int64_t(m.vertices.size()) + 1;  // relative to the vertices read so far
            if (i < 1 || i > int64_t(UINT32_MAX)) throw InputError(path, ln, "face index out of range");
            if (uint64_t(i) > m.vertices.size()) pending = true;
            if (n < 3) tri[n] = uint32_t(i - 1);
            ++n;
          }
          if (n != 3)
            throw InputError(path, ln, "face with " + std::to_string(n) + " vertices (only triangles are read)");
          if (pending) forward.push_back({m.triangles.size(), ln});
          m.triangles.push_back(tri);
          return true;
        }
        static const char* ignored[] = {"vn", "vt", "vp", "o", "g", "s", "usemtl", "mtllib", "l", "p"};
        for (const char* k : ignored)
          if (key == k) return true;
        throw InputError(path, ln, "unknown OBJ statement " + shown(key));
      },
      pos, line_no);
  for (const Pending& p : forward)
    for (uint32_t v : m.triangles[p.triangle])
      if (v >= m.vertices.size())
        throw InputError(path, p.line,
                         "face index " + std::to_string(v + 1) + " but only " + std::to_string(m.vertices.size()) +
                             " vertices");
  return m;
}

// ---- PLY ----

enum class Scalar { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

bool scalar_of(std::string_view name, Scalar& s) {
  static const std::pair<const char*, Scalar> names[] = {
      {"char", Scalar::Int8},     {"int8", Scalar::Int8},       {"uchar", Scalar::Uint8},
      {"uint8", Scalar::Uint8},   {"short", Scalar::Int16},     {"int16", Scalar::Int16},
      {"ushort", Scalar::Uint16}, {"uint16", Scalar::Uint16},   {"int", Scalar::Int32},
      {"int32", Scalar::Int32},   {"uint", Scalar::Uint32},     {"uint32", Scalar::Uint32},
      {"float", Scalar::Float32}, {"float32", Scalar::Float32}, {"double", Scalar::Float64},
      {"float64", Scalar::Float64}};
  for (const auto& [n, v] : names)
    if (name == n) {
      s = v;
      return true;
    }
  return false;
}

size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::Int8:
    case Scalar::Uint8: return 1;
    case Scalar::Int16:
    case Scalar::Uint16: return 2;
    case Scalar::Int32:
    case Scalar::Uint32:
    case Scalar::Float32: return 4;
    case Scalar::Float64: return 8;
  }
  return 0;
}

bool is_float(Scalar s) { return s == Scalar::Float32 || s == Scalar::Float64; }

struct Property {
  std::string name;
  bool list = false;
  Scalar count_type = Scalar::Uint8;
  Scalar type = Scalar::Float64;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class PlyFormat { Ascii, BinaryLe, BinaryBe };

// Reads one binary scalar as double (exact for every PLY type) from data at pos.
class BinaryReader {
 public:
  BinaryReader(const std::string& path, std::string_view data, size_t pos, bool big_endian)
      : path_(path), data_(data), pos_(pos), swap_(big_endian) {}

  double read(Scalar s, const std::string& element, uint64_t index) {
    const size_t n = scalar_size(s);
    if (pos_ + n > data_.size())
      throw InputError(path_, 0, "file ends inside " + element + " " + std::to_string(index));
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (swap_) std::reverse(b, b + n);
    switch (s) {
      case Scalar::Int8: return double(int8_t(b[0]));
      case Scalar::Uint8: return double(b[0]);
      case Scalar::Int16: return double(load<int16_t>(b));
      case Scalar::Uint16: return double(load<uint16_t>(b));
      case Scalar::Int32: return double(load<int32_t>(b));
      case Scalar::Uint32: return double(load<uint32_t>(b));
      case Scalar::Float32: return double(load<float>(b));
      case Scalar::Float64: return load<double>(b);
    }
    return 0;
  }
  size_t pos() const { return pos_; }

 private:
  template <class T>
  static T load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof v);
    return v;
  }
  const std::string& path_;
  std::string_view data_;
  size_t pos_;
  bool swap_;
};

// Reads ascii PLY values token by token, keeping track of the line for messages.
class AsciiReader {
 public:
  AsciiReader(const std::string& path, std::string_view data, size_t pos, uint64_t line)
      : path_(path), data_(data), pos_(pos), line_(line) {}

  double read(Scalar s, const std::string& element, uint64_t index) {
    while (pos_ < data_.size() && (is_space(data_[pos_]) || data_[pos_] == '\n')) {
      if (data_[pos_] == '\n') ++line_;
      ++pos_;
    }
    const size_t b = pos_;
    while (pos_ < data_.size() && !is_space(data_[pos_]) && data_[pos_] != '\n') ++pos_;
    const std::string_view t = data_.substr(b, pos_ - b);
    auto what = [&] { return element + " " + std::to_string(index); };
    if (t.empty()) {
      // At the end of the file: name its last line.
      const bool ends_with_newline = !data_.empty() && data_.back() == '\n';
      throw InputError(path_, ends_with_newline ? line_ : line_ + 1, "file ends inside " + what());
    }
    double v = 0;
    if (is_float(s)) {
      if (!parse_double(t, v)) throw InputError(path_, line_ + 1, "bad number " + shown(t) + " in " + what());
    } else {
      int64_t i = 0;
      if (!parse_int(t, i)) throw InputError(path_, line_ + 1, "bad integer " + shown(t) + " in " + what());
      v = double(i);
    }
    return v;
  }

 private:
  const std::string& path_;
  std::string_view data_;
  size_t pos_;
  uint64_t line_;  // lines before the current one
};

template <class Reader>
void read_ply_body(const std::string& path, const std::vector<Element>& elements, Reader& r, Mesh& m,
                   uint64_t body_bytes) {
  for (const Element& e : elements) {
    // Every value takes at least a byte, so a row count beyond the body's size is damage (and would be a loop of
    // trillions of rows or a huge reservation). Rows without properties hold nothing to read.
    if (e.properties.empty()) continue;
    if (e.count > body_bytes / e.properties.size())
      throw InputError(path, 0, "PLY element '" + e.name + "' declares " + std::to_string(e.count) +
                                    " rows, more than the rest of the file can hold");
    const bool vertex = e.name == "vertex", face = e.name == "face";
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (vertex && !p.list && p.name.size() == 1 && p.name[0] >= 'x' && p.name[0] <= 'z') xyz[p.name[0] - 'x'] = int(k);
      if (face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) indices = int(k);
    }
    if (vertex && (xyz[0] < 0 || xyz[1] < 0)) throw InputError(path, 0, "PLY vertex element has no x and y");
    if (face && indices < 0) throw InputError(path, 0, "PLY face element has no vertex_indices list");
    if (vertex) m.vertices.reserve(e.count);
    if (face) m.triangles.reserve(e.count);
    for (uint64_t i = 0; i < e.count; ++i) {
      auto what = [&] { return e.name + " " + std::to_string(i); };
      Point3 p;
      Triangle tri{};
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const Property& prop = e.properties[k];
        if (!prop.list) {
          const double v = r.read(prop.type, e.name, i);
          if (vertex && int(k) == xyz[0]) p.x = v;
          if (vertex && int(k) == xyz[1]) p.y = v;
          if (vertex && int(k) == xyz[2]) p.z = v;
          continue;
        }
        const double n = r.read(prop.count_type, e.name, i);
        if (!(n >= 0)) throw InputError(path, 0, what() + ": negative list length");
        if (int(k) == indices && n != 3)
          throw InputError(path, 0, what() + " has " + std::to_string(int64_t(n)) + " vertices (only triangles are read)");
        for (uint64_t j = 0; j < uint64_t(n); ++j) {
          const double v = r.read(prop.type, e.name, i);
          if (int(k) != indices) continue;
          if (!(v >= 0 && v < double(m.vertices.size())) || v != std::floor(v))
            throw InputError(path, 0,
                             what() + ": vertex index " + std::to_string(int64_t(v)) + " out of range (" +
                                 std::to_string(m.vertices.size()) + " vertices read before it)");
          tri[j] = uint32_t(v);
        }
      }
      if (vertex) m.vertices.push_back(p);
      if (face) m.triangles.push_back(tri);
    }
  }
}

Mesh read_ply(const std::string& path, std::string_view text) {
  size_t pos = 0;
  uint64_t line_no = 0;
  bool ended = false, magic = false;
  PlyFormat format = PlyFormat::Ascii;
  bool has_format = false;
  std::vector<Element> elements;
  for_lines(
      text,
      [&](std::string_view line, uint64_t ln) {
        Tokens tk{line};
        const std::string_view key = tk.next();
        if (!magic) {
          if (key != "ply") throw InputError(path, ln, "not a PLY file (no 'ply' line)");
          magic = true;
          return true;
        }
        if (key == "end_header") {
          ended = true;
          return false;
        }
        if (key.empty() || key == "comment" || key == "obj_info") return true;
        if (key == "format") {
          const std::string_view f = tk.next();
          if (f == "ascii") format = PlyFormat::Ascii;
          else if (f == "binary_little_endian") format = PlyFormat::BinaryLe;
          else if (f == "binary_big_endian") format = PlyFormat::BinaryBe;
          else throw InputError(path, ln, "unknown PLY format " + shown(f));
          has_format = true;
          return true;
        }
        if (key == "element") {
          Element e;
          e.name = std::string(tk.next());
          if (!parse_int(tk.next(), e.count)) throw InputError(path, ln, "bad element count");
          elements.push_back(std::move(e));
          return true;
        }
        if (key == "property") {
          if (elements.empty()) throw InputError(path, ln, "property before any element");
          Property p;
          std::string_view t = tk.next();
          if (t == "list") {
            p.list = true;
            const std::string_view c = tk.next();
            if (!scalar_of(c, p.count_type) || is_float(p.count_type))
              throw InputError(path, ln, "bad list count type " + shown(c));
            t = tk.next();
          }
          if (!scalar_of(t, p.type)) throw InputError(path, ln, "unknown property type " + shown(t));
          p.name = std::string(tk.next());
          elements.back().properties.push_back(std::move(p));
          return true;
        }
        throw InputError(path, ln, "unknown PLY header line " + shown(key));
      },
      pos, line_no);
  if (!magic) throw InputError(path, 0, "not a PLY file (empty)");
  if (!ended) throw InputError(path, 0, "PLY header has no end_header");
  if (!has_format) throw InputError(path, 0, "PLY header has no format line");
  Mesh m;
  if (format == PlyFormat::Ascii) {
    AsciiReader r(path, text, pos, line_no);
    read_ply_body(path, elements, r, m, text.size() - pos);
  } else {
    BinaryReader r(path, text, pos, format == PlyFormat::BinaryBe);
    read_ply_body(path, elements, r, m, text.size() - pos);
  }
  return m;
}

// ---- WKT ----

struct PointHash {
  size_t operator()(const Point3& p) const {
    const uint64_t a = std::bit_cast<uint64_t>(p.x), b = std::bit_cast<uint64_t>(p.y),
                   c = std::bit_cast<uint64_t>(p.z);
    return size_t((a * 0x9E3779B97F4A7C15ull) ^ (b * 0xC2B2AE3D27D4EB4Full) ^ (c * 0x165667B19E3779F9ull));
  }
};
// Exact equality of the bits: 0 and -0 stay two values, so a written mesh reads back bit for bit.
struct PointBitsEqual {
  bool operator()(const Point3& p, const Point3& q) const {
    return std::memcmp(&p, &q, sizeof p) == 0;
  }
};

class WktParser {
 public:
  WktParser(const std::string& path, std::string_view text) : path_(path), s_(text) {}

  Mesh parse() {
    skip();
    const std::string word = lower(std::string(ident()));
    if (word != "tin" && word != "multipolygon" && word != "polyhedralsurface")
      throw error("expected TIN Z, MULTIPOLYGON Z or POLYHEDRALSURFACE Z, found " + shown(word));
    skip();
    std::string dim = lower(std::string(peek_ident()));
    if (dim == "z") ident();
    else if (dim == "m" || dim == "zm") throw error("M coordinates are not supported");
    skip();
    if (lower(std::string(peek_ident())) == "empty") {
      ident();
      finish();
      return {};
    }
    expect('(');
    do read_triangle();
    while (comma());
    expect(')');
    finish();
    return build();
  }

 private:
  InputError error(const std::string& what) const {
    return InputError(path_, line_, what + " (character " + std::to_string(col()) + ")");
  }
  size_t col() const {
    const size_t nl = s_.rfind('\n', i_ == 0 ? 0 : i_ - 1);
    return nl == std::string_view::npos ? i_ + 1 : i_ - nl;
  }
  void skip() {
    while (i_ < s_.size() && (is_space(s_[i_]) || s_[i_] == '\n')) {
      if (s_[i_] == '\n') ++line_;
      ++i_;
    }
  }
  std::string_view peek_ident() const {
    size_t j = i_;
    while (j < s_.size() && std::isalpha(static_cast<unsigned char>(s_[j]))) ++j;
    return s_.substr(i_, j - i_);
  }
  std::string_view ident() {
    const std::string_view w = peek_ident();
    i_ += w.size();
    return w;
  }
  void expect(char c) {
    skip();
    if (i_ >= s_.size() || s_[i_] != c)
      throw error(std::string("expected '") + c + "'" + (i_ < s_.size() ? "" : " before the end of the file"));
    ++i_;
  }
  bool comma() {
    skip();
    if (i_ < s_.size() && s_[i_] == ',') {
      ++i_;
      return true;
    }
    return false;
  }
  void finish() {
    skip();
    if (i_ < s_.size() && s_[i_] == ';') ++i_;
    skip();
    if (i_ < s_.size()) throw error("unexpected text after the geometry (one geometry per file)");
  }
  double number() {
    skip();
    size_t j = i_;
    while (j < s_.size() && s_[j] != ',' && s_[j] != ')' && s_[j] != '(' && s_[j] != '\n' && !is_space(s_[j])) ++j;
    const std::string_view t = s_.substr(i_, j - i_);
    double v = 0;
    if (!parse_double(t, v)) throw error(t.empty() ? "expected a number" : "bad number " + shown(t));
    i_ = j;
    return v;
  }
  Point3 point() {
    Point3 p;
    p.x = number();
    p.y = number();
    p.z = number();
    return p;
  }
  // "((a, b, c, a))": one ring of four points, the last repeating the first.
  void read_triangle() {
    ++polygons_;
    expect('(');
    expect('(');
    Point3 ring[4];
    int n = 0;
    do {
      if (n == 4) throw error("polygon " + std::to_string(polygons_) + " is not a triangle (more than 4 points)");
      ring[n++] = point();
    } while (comma());
    expect(')');
    skip();
    if (i_ < s_.size() && s_[i_] == ',') throw error("polygon " + std::to_string(polygons_) + " has a hole");
    expect(')');
    if (n != 4 || !PointBitsEqual()(ring[0], ring[3]))
      throw error("polygon " + std::to_string(polygons_) + " is not a closed triangle (4 points, last = first)");
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      auto [it, inserted] = index_.try_emplace(ring[k], uint32_t(vertices_.size()));
      if (inserted) vertices_.push_back(ring[k]);
      t[k] = it->second;
    }
    triangles_.push_back(t);
  }
  // Vertices in canonical order (x, y, then z and bits for a full order), so a canonical mesh reads back
  // identical; triangles keep their order and their first vertex.
  Mesh build() {
    std::vector<uint32_t> order(vertices_.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    auto key = [&](uint32_t i) {
      const Point3& p = vertices_[i];
      return std::make_tuple(p.x, p.y, p.z, std::bit_cast<uint64_t>(p.x), std::bit_cast<uint64_t>(p.y),
                             std::bit_cast<uint64_t>(p.z));
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    std::vector<uint32_t> rank(order.size());
    Mesh m;
    m.vertices.reserve(order.size());
    for (uint32_t r = 0; r < order.size(); ++r) {
      rank[order[r]] = r;
      m.vertices.push_back(vertices_[order[r]]);
    }
    m.triangles = std::move(triangles_);
    for (Triangle& t : m.triangles)
      for (uint32_t& v : t) v = rank[v];
    return m;
  }

  const std::string& path_;
  std::string_view s_;
  size_t i_ = 0;
  uint64_t line_ = 1;
  uint64_t polygons_ = 0;
  Points vertices_;
  Triangles triangles_;
  std::unordered_map<Point3, uint32_t, PointHash, PointBitsEqual> index_;
};

}  // namespace

Mesh read_mesh_file(const std::string& path) {
  MeshFormat format;
  try {
    format = format_from_extension(path);
  } catch (const UsageError&) {
    throw InputError(path, 0, "unknown mesh format (expected .obj, .ply, .wkt, .xml or .2dm)");
  }
  const std::string data = slurp(path);
  switch (format) {
    case MeshFormat::Obj: return read_obj(path, data);
    case MeshFormat::Ply: return read_ply(path, data);
    case MeshFormat::Wkt: return WktParser(path, data).parse();
    case MeshFormat::LandXml: return read_landxml(path, data);
    case MeshFormat::Sms2dm: return read_2dm(path, data);
  }
  return {};
}

}  // namespace cdtgpu
