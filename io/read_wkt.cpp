// WKT reader: POINT, MULTIPOINT, LINESTRING, MULTILINESTRING, POLYGON, MULTIPOLYGON (and GEOMETRYCOLLECTION
// of them), 2D (z = 0), Z, M (ignored) or ZM, one geometry per line or one spanning lines while a '(' is
// open.
//
// A small tokenizer of our own rather than CGAL/IO/WKT.h (see ../shared/notes/io.md): CGAL 5.5's read_WKT
// returned false on a valid three-line file and reports no position, read_polygon_WKT rejects POLYGON Z
// (building footprints with heights), and it takes "nan" as a coordinate. Using CGAL for some types and this
// for the rest would give two grammars and two error paths; this one names the line of every error.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "io/readers.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }
bool ends_token(char c) { return is_space(c) || c == ',' || c == '(' || c == ')' || c == ';'; }

enum class Dim { unknown, xy, xyz, xym, xyzm };

// One geometry's text, possibly several lines, starting at line `first_line` of the source.
class Parser {
 public:
  Parser(std::string_view text, uint64_t first_line, const std::string& name, uint32_t source, InputSet& in)
      : s_(text), first_line_(first_line), name_(name), source_(source), in_(in) {}

  // Parses every geometry in the text (normally one).
  void parse_all() {
    for (skip_space(); i_ < s_.size(); skip_space()) {
      first_count_ = 0;
      geometry();
    }
  }

 private:
  uint64_t line() const {
    // At the end of the text there is no token: name the line of the last one instead.
    size_t stop = std::min(i_, s_.size());
    if (stop == s_.size())
      while (stop > 0 && is_space(s_[stop - 1])) --stop;
    uint64_t n = first_line_;
    for (size_t k = 0; k < stop; ++k) n += s_[k] == '\n';
    return n;
  }

  [[noreturn]] void fail(const std::string& what) const {
    const uint64_t at = line();
    throw InputError(
        name_, at,
        what + (at != first_line_ ? " (geometry starts at line " + std::to_string(first_line_) + ")"
                                  : std::string()));
  }

  std::string next_token_text() const {
    if (i_ >= s_.size()) return "end of input";
    size_t k = i_;
    while (k < s_.size() && !ends_token(s_[k])) ++k;
    std::string t = "'";
    t += s_.substr(i_, std::max<size_t>(k - i_, 1));
    t += '\'';
    return t;
  }

  void skip_space() {
    while (i_ < s_.size() && is_space(s_[i_])) ++i_;
  }

  bool eat(char c) {
    skip_space();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }

  void expect(char c) {
    if (!eat(c)) fail(std::string("expected '") + c + "', found " + next_token_text());
  }

  // A keyword in upper case; empty when the next token does not start with a letter.
  std::string word() {
    skip_space();
    std::string w;
    while (i_ < s_.size() && std::isalpha(static_cast<unsigned char>(s_[i_])))
      w += char(std::toupper(static_cast<unsigned char>(s_[i_++])));
    return w;
  }

  bool peek_word(std::string_view w) {
    skip_space();
    size_t k = 0;
    while (k < w.size() && i_ + k < s_.size() && std::toupper(static_cast<unsigned char>(s_[i_ + k])) == w[k])
      ++k;
    if (k != w.size() || (i_ + k < s_.size() && !ends_token(s_[i_ + k]))) return false;
    i_ += k;
    return true;
  }

  // EMPTY, or the opening '(' of a body.
  bool open_or_empty() {
    if (peek_word("EMPTY")) return false;
    expect('(');
    return true;
  }

  Point3 coordinate(Dim dim) {
    double v[4];
    int n = 0;
    skip_space();
    const size_t start = i_;
    while (i_ < s_.size() && s_[i_] != ',' && s_[i_] != ')') {
      if (n == 4) fail("too many numbers in a coordinate");
      const char* p = s_.data() + i_;
      const char* end = s_.data() + s_.size();
      if (*p == '+' && p + 1 < end && p[1] != '-') ++p;  // from_chars rejects a leading '+'
      auto [q, ec] = std::from_chars(p, end, v[n]);
      if (ec == std::errc::result_out_of_range) fail("number out of range: " + next_token_text());
      if (ec != std::errc() || (q < end && !ends_token(*q))) {
        if (n >= 2) break;  // a complete coordinate: let the caller say which ',' or ')' is missing
        fail("expected a number, found " + next_token_text());
      }
      i_ = size_t(q - s_.data());
      ++n;
      skip_space();
    }
    // Untagged, every coordinate must have as many numbers as the first: "1 1 0 0" for "1 1, 0 0" is a
    // missing comma, not an XYZM coordinate.
    const int want = dim == Dim::xy                       ? 2
                     : dim == Dim::xyz || dim == Dim::xym ? 3
                     : dim == Dim::xyzm                   ? 4
                                                          : first_count_;
    if (want ? n != want : n < 2) {
      i_ = start;
      fail("expected " + (want ? std::to_string(want) : std::string("2 to 4")) +
           " numbers in a coordinate, found " + std::to_string(n));
    }
    if (first_count_ == 0) first_count_ = n;
    const bool has_z = dim == Dim::xyz || dim == Dim::xyzm || (dim == Dim::unknown && n >= 3);
    const Point3 p{v[0], v[1], has_z ? v[2] : 0.0};
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      i_ = start;  // name the line of the coordinate itself, which may follow the geometry's first line
      fail("coordinate is not a finite number");
    }
    if (!has_z && in_.nan_for_missing_z) return {p.x, p.y, missing_z()};
    return p;
  }

  // '(' coordinate, ... ')' (the opening '(' already eaten).
  Points coordinates(Dim dim) {
    Points pts;
    do pts.push_back(coordinate(dim));
    while (eat(','));
    expect(')');
    return pts;
  }

  void line_string(Dim dim, bool closed) {
    if (!open_or_empty()) return;
    add_polyline(in_, Polyline{coordinates(dim), closed, source_, first_line_});
  }

  void polygon(Dim dim) {
    if (!open_or_empty()) return;
    do line_string(dim, true);
    while (eat(','));
    expect(')');
  }

  void multi_point(Dim dim) {
    if (!open_or_empty()) return;
    do {
      if (peek_word("EMPTY")) continue;
      // Both MULTIPOINT ((1 2), (3 4)) and MULTIPOINT (1 2, 3 4) are in use.
      const bool wrapped = eat('(');
      add_point(in_, source_, first_line_, coordinate(dim));
      if (wrapped) expect(')');
    } while (eat(','));
    expect(')');
  }

  template <typename Part>
  void multi(Part part) {
    if (!open_or_empty()) return;
    do part();
    while (eat(','));
    expect(')');
  }

  void geometry() {
    std::string type = word();
    if (type == "SRID") {  // EWKT prefix "SRID=4326;": the CRS comes from options, not from here
      expect('=');
      while (i_ < s_.size() && s_[i_] != ';' && !is_space(s_[i_])) ++i_;
      expect(';');
      type = word();
    }
    if (type.empty()) fail("expected a geometry type, found " + next_token_text());
    Dim dim = Dim::unknown;
    // The dimension is a separate word (POINT Z) or, in some writers, a suffix (POINTZ).
    auto strip = [&](std::string_view suffix, Dim d) {
      if (dim == Dim::unknown && type.size() > suffix.size() && type.ends_with(suffix) &&
          is_type(type.substr(0, type.size() - suffix.size()))) {
        type.resize(type.size() - suffix.size());
        dim = d;
      }
    };
    strip("ZM", Dim::xyzm);
    strip("Z", Dim::xyz);
    strip("M", Dim::xym);
    if (!is_type(type)) fail("unknown geometry type '" + type + "'");
    if (dim == Dim::unknown) {
      if (peek_word("ZM"))
        dim = Dim::xyzm;
      else if (peek_word("Z"))
        dim = Dim::xyz;
      else if (peek_word("M"))
        dim = Dim::xym;
    }
    if (type == "POINT") {
      if (open_or_empty()) {
        add_point(in_, source_, first_line_, coordinate(dim));
        expect(')');
      }
    } else if (type == "LINESTRING") {
      line_string(dim, false);
    } else if (type == "POLYGON") {
      polygon(dim);
    } else if (type == "MULTIPOINT") {
      multi_point(dim);
    } else if (type == "MULTILINESTRING") {
      multi([&] { line_string(dim, false); });
    } else if (type == "MULTIPOLYGON") {
      multi([&] { polygon(dim); });
    } else {
      if (++nesting_ > 32) fail("geometry collections nested too deeply");  // bounds the recursion
      multi([&] { geometry(); });
      --nesting_;
    }
  }

  static bool is_type(std::string_view t) {
    return t == "POINT" || t == "LINESTRING" || t == "POLYGON" || t == "MULTIPOINT" ||
           t == "MULTILINESTRING" || t == "MULTIPOLYGON" || t == "GEOMETRYCOLLECTION";
  }

  std::string_view s_;
  size_t i_ = 0;
  int first_count_ = 0;  // numbers in the first coordinate of an untagged geometry
  int nesting_ = 0;
  uint64_t first_line_;
  const std::string& name_;
  uint32_t source_;
  InputSet& in_;
};

}  // namespace

namespace {

// Parses the geometries that start in text[c.begin, c.end). One that is still open at c.end is read on past it;
// text before the first geometry start (the end of one begun in an earlier chunk, `depth` > 0 parentheses
// still open) is skipped.
void parse_wkt_chunk(std::string_view text, const Chunk& c, long depth, const std::string& name, uint32_t source,
                     InputSet& in) {
  size_t p = c.begin, start = 0;  // start: first byte of the pending geometry
  uint64_t line_no = c.first_line, start_line = 0;
  bool pending = false;
  while (p < text.size() && (p < c.end || pending)) {
    const void* nl = std::memchr(text.data() + p, '\n', text.size() - p);
    const size_t e = nl ? size_t(static_cast<const char*>(nl) - text.data()) : text.size();
    const std::string_view line = text.substr(p, e - p);
    const bool skipping = depth > 0 && !pending;  // the tail of a geometry owned by an earlier chunk
    if (!skipping && !pending) {
      if (line.find_first_not_of(" \t\r\v\f") == std::string_view::npos) {
        p = e + 1, ++line_no;
        continue;
      }
      pending = true, start = p, start_line = line_no;
    }
    for (char ch : line) depth += (ch == '(') - (ch == ')');
    if (depth <= 0) {
      if (pending) Parser(text.substr(start, std::min(e + 1, text.size()) - start), start_line, name, source, in).parse_all();
      pending = false;
      depth = 0;
    }
    p = e + 1, ++line_no;
  }
  if (pending) Parser(text.substr(start), start_line, name, source, in).parse_all();  // reports the unclosed '('
}

}  // namespace

void read_wkt_text(std::string_view text, const std::string& name, InputSet& in) {
  in.sources.push_back(name);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  const size_t before = in.points.size() + in.lines.size();
  const std::vector<Chunk> chunks = split_lines(text, chunk_bytes(text.size()));
  // Parentheses open at each chunk's start: a running sum of every earlier chunk's balance. Valid input never
  // goes below zero, and invalid input fails in the geometry where it does, so the sum is exact up to the
  // first error, the one reported.
  std::vector<long> open(chunks.size() + 1, 0);
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t k) {
    long d = 0;
    for (size_t i = chunks[k].begin; i < chunks[k].end; ++i) d += (text[i] == '(') - (text[i] == ')');
    open[k + 1] = d;
  });
  for (size_t k = 0; k < chunks.size(); ++k) open[k + 1] += open[k];
  std::vector<InputSet> parts(chunks.size());
  parse_chunks(chunks, [&](size_t k, const Chunk& c) {
    parts[k] = chunk_part(in, source, name);
    parse_wkt_chunk(text, c, std::max(0L, open[k]), name, source, parts[k]);
  });
  append_parts(in, parts);
  if (in.points.size() + in.lines.size() == before) throw InputError(name, 0, "no geometry");
}

void read_wkt(std::istream& text, const std::string& name, InputSet& in) {
  const TextSource src = TextSource::read(text, name);
  read_wkt_text(src.text(), name, in);
}

}  // namespace cdtgpu
