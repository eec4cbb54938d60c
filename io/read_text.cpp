// Point readers for plain text: XYZ/CSV ("x y z" per line) and ESRI ASCII grids (.asc, one vertex per cell).
// Numbers go through std::from_chars: locale-free, exact (round-trips what a %.17g writer printed) and fast.
// Both parse on all cores; a grid whose data has any fault is read again by the sequential reader, whose
// message (the first fault in the file) is the one reported.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <tbb/parallel_for.h>

#include <atomic>
#include <sstream>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "core/touched.hpp"
#include "io/read_share.hpp"
#include "io/readers.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
bool is_separator(char c) { return c == ',' || c == ';'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// Drops a UTF-8 byte order mark (spreadsheet exports start with one).
void strip_bom(std::string& line) {
  if (line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
}

enum class Parse { ok, not_a_number, out_of_range };

// Parses a number that must end at `end` or at a character for which `stop` holds.
template <typename Stop>
Parse parse_number(const char*& p, const char* end, double& v, Stop stop) {
  const char* s = p;
  if (s < end && *s == '+' && s + 1 < end && s[1] != '-') ++s;  // from_chars rejects a leading '+'
  auto [q, ec] = std::from_chars(s, end, v);
  if (ec == std::errc::result_out_of_range) return Parse::out_of_range;
  if (ec != std::errc() || (q < end && !stop(*q))) return Parse::not_a_number;
  p = q;
  return Parse::ok;
}

std::string token_at(const char* p, const char* end) {
  const char* q = p;
  while (q < end && !is_space(*q) && !is_separator(*q)) ++q;
  return std::string(p, q);
}

// An input that gave nothing to triangulate is a mistake (wrong file, wrong format), not an empty TIN.
void require_geometry(const InputSet& in, size_t before, const std::string& name) {
  if (in.points.size() + in.lines.size() == before) throw InputError(name, 0, "no geometry");
}

uint32_t add_source(InputSet& in, const std::string& name) {
  in.sources.push_back(name);
  return uint32_t(in.sources.size() - 1);
}

}  // namespace

namespace {

enum class XyzLine { point, skip, header };

// One line of XYZ text. Only the first line with content may be a header (its first field not a number).
XyzLine parse_xyz_line(const char* p, const char* end, bool may_be_header, uint64_t line_no,
                       const std::string& name, Point3& point) {
  auto field_end = [](char c) { return is_space(c) || is_separator(c); };
  while (p < end && is_space(*p)) ++p;
  if (p == end || *p == '#') return XyzLine::skip;
  double v[3];
  int n = 0;
  for (; n < 3; ++n) {
    while (p < end && is_space(*p)) ++p;
    if (n > 0 && p < end && is_separator(*p)) {
      ++p;
      while (p < end && is_space(*p)) ++p;
    }
    if (p == end) break;
    const char* start = p;
    const Parse r = parse_number(p, end, v[n], field_end);
    if (r == Parse::ok) continue;
    if (n == 0 && may_be_header && r == Parse::not_a_number) return XyzLine::header;
    if (r == Parse::out_of_range)
      throw InputError(name, line_no, "number out of range in column " + std::to_string(n + 1));
    const std::string tok = token_at(start, end);
    throw InputError(name, line_no,
                     "column " + std::to_string(n + 1) +
                         (tok.empty() ? std::string(" is empty") : " is not a number: '" + tok + "'"));
  }
  if (n < 3)
    throw InputError(name, line_no, "expected x y z, found " + std::to_string(n) + " number" + (n == 1 ? "" : "s"));
  point = Point3{v[0], v[1], v[2]};
  return XyzLine::point;
}

// Calls f(line_begin, line_end) for every line of text[begin, end); returns the position after the last.
template <typename F>
void for_each_line(std::string_view text, size_t begin, size_t end, F&& f) {
  const char* p = text.data() + begin;
  const char* stop = text.data() + end;
  while (p < stop) {
    const char* nl = static_cast<const char*>(std::memchr(p, '\n', size_t(stop - p)));
    const char* e = nl ? nl : stop;
    if (!f(p, e)) return;
    p = e + 1;
  }
}

}  // namespace

namespace {

// Reads the points of `text` (whole lines) into `in`, line numbers from 1. Its first line with content is a
// header when its first field is not a number and header_allowed() says it may be one.
void read_xyz_lines(std::string_view text, const std::function<bool()>& header_allowed, uint32_t source,
                    const std::string& name, InputSet& in) {
  // The first line with content, alone: it may be a header. Every later line is a point, blank or a comment.
  uint64_t line_no = 0;
  size_t rest = text.size();
  for_each_line(text, 0, text.size(), [&](const char* b, const char* e) {
    ++line_no;
    Point3 p;
    XyzLine kind = parse_xyz_line(b, e, true, line_no, name, p);
    if (kind == XyzLine::skip) return true;
    if (kind == XyzLine::header && !header_allowed()) kind = parse_xyz_line(b, e, false, line_no, name, p);
    if (kind == XyzLine::point) add_point(in, source, line_no, p);
    rest = std::min(text.size(), size_t(e - text.data()) + 1);
    return false;
  });
  const std::vector<Chunk> chunks = split_lines(text.substr(rest), chunk_bytes(text.size() - rest), line_no + 1);
  std::vector<InputSet> parts(chunks.size());
  parse_chunks(chunks, [&](size_t k, const Chunk& c) {
    InputSet& part = parts[k] = chunk_part(in, source, name);
    part.points.reserve((c.end - c.begin) / 16);
    uint64_t line = c.first_line;
    for_each_line(text.substr(rest), c.begin, c.end, [&](const char* b, const char* e) {
      Point3 p;
      if (parse_xyz_line(b, e, false, line, name, p) == XyzLine::point) add_point(part, source, line, p);
      ++line;
      return true;
    });
  });
  append_parts(in, parts);
}

// Whether some line of text has content (not blank, not a comment).
bool has_content(std::string_view text) {
  bool found = false;
  for_each_line(text, 0, text.size(), [&](const char* b, const char* e) {
    while (b < e && is_space(*b)) ++b;
    found = b < e && *b != '#';
    return !found;
  });
  return found;
}

}  // namespace

void read_xyz_text(std::string_view text, const std::string& name, InputSet& in, const ReadShare* share) {
  const uint32_t source = add_source(in, name);
  const size_t before = in.points.size() + in.lines.size();
  if (!share) {
    read_xyz_lines(text, [] { return true; }, source, name, in);
    require_geometry(in, before, name);
    return;
  }
  // A share of the lines; whether some share has points is for the caller to say once they are joined. Only
  // errors need the lines before the share: its line numbers count from its own start.
  const auto [begin, end] = share_lines(text, *share);
  const std::string_view prefix = text.substr(0, begin);
  try {
    read_xyz_lines(text.substr(begin, end - begin), [&] { return !has_content(prefix); }, source, name, in);
  } catch (const InputError& e) {
    if (begin == 0 || e.record == 0) throw;
    throw InputError(name, e.record + uint64_t(std::count(prefix.begin(), prefix.end(), '\n')), e.detail);
  }
}

void read_xyz(std::istream& text, const std::string& name, InputSet& in) {
  const TextSource src = TextSource::read(text, name);
  read_xyz_text(src.text(), name, in);
}

namespace {

struct GridHeader {
  int64_t ncols = -1, nrows = -1;
  double xll = NAN, yll = NAN, cellsize = NAN, dx = NAN, dy = NAN, nodata = NAN;
  bool x_center = false, y_center = false, has_nodata = false;
};

bool starts_number(char c) { return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.'; }

// Reads "key value" header lines; returns false on the first line that starts with a number (the data).
bool read_header_line(std::string_view line, uint64_t line_no, const std::string& name, GridHeader& h) {
  size_t k = 0;
  while (k < line.size() && !is_space(line[k])) ++k;
  std::string key(line.substr(0, k));
  if (starts_number(key[0])) return false;
  for (char& c : key) c = char(std::tolower(static_cast<unsigned char>(c)));
  const std::string_view value = trim(line.substr(k));
  if (value.empty()) throw InputError(name, line_no, "header '" + key + "' has no value");
  const char* p = value.data();
  const char* end = p + value.size();
  if (key == "ncols" || key == "nrows") {
    int64_t n = 0;
    auto [q, ec] = std::from_chars(p, end, n);
    if (ec != std::errc() || q != end || n <= 0)
      throw InputError(name, line_no, key + " must be a positive integer, not '" + std::string(value) + "'");
    (key == "ncols" ? h.ncols : h.nrows) = n;
    return true;
  }
  double v = 0;
  // NODATA_value may be nan (some writers use it); every other value must be finite.
  if (parse_number(p, end, v, [](char) { return false; }) != Parse::ok ||
      (!std::isfinite(v) && key != "nodata_value"))
    throw InputError(name, line_no, key + " must be a finite number, not '" + std::string(value) + "'");
  if (key == "xllcorner" || key == "xllcenter") {
    h.xll = v;
    h.x_center = key == "xllcenter";
  } else if (key == "yllcorner" || key == "yllcenter") {
    h.yll = v;
    h.y_center = key == "yllcenter";
  } else if (key == "cellsize" || key == "dx" || key == "dy") {
    if (v <= 0) throw InputError(name, line_no, key + " must be positive");
    (key == "cellsize" ? h.cellsize : key == "dx" ? h.dx : h.dy) = v;
  } else if (key == "nodata_value") {
    h.nodata = v;
    h.has_nodata = true;
  } else {
    throw InputError(name, line_no, "unknown header key '" + key + "'");
  }
  return true;
}

void check_header(GridHeader& h, uint64_t line_no, const std::string& name) {
  std::string missing;
  if (h.ncols < 0) missing += " ncols";
  if (h.nrows < 0) missing += " nrows";
  if (std::isnan(h.xll)) missing += " xllcorner|xllcenter";
  if (std::isnan(h.yll)) missing += " yllcorner|yllcenter";
  if (!std::isnan(h.cellsize)) {
    if (std::isnan(h.dx)) h.dx = h.cellsize;
    if (std::isnan(h.dy)) h.dy = h.cellsize;
  }
  if (std::isnan(h.dx) || std::isnan(h.dy)) missing += " cellsize|dx+dy";
  if (!missing.empty()) throw InputError(name, line_no, "grid header lacks" + missing);
}

}  // namespace

void read_ascii_grid(std::istream& text, const std::string& name, InputSet& in) {
  const uint32_t source = add_source(in, name);
  const size_t before = in.points.size() + in.lines.size();
  GridHeader h;
  std::string line;
  uint64_t line_no = 0;
  bool in_data = false, any_text = false;
  while (!in_data && std::getline(text, line)) {
    ++line_no;
    if (line_no == 1) strip_bom(line);
    const std::string_view s = trim(line);
    if (s.empty()) continue;
    any_text = true;
    in_data = !read_header_line(s, line_no, name, h);
  }
  if (!any_text) throw InputError(name, 0, "no geometry");
  if (!in_data) {
    check_header(h, line_no, name);
    throw InputError(name, line_no, "grid has no data rows");
  }
  check_header(h, line_no, name);

  // Cell centres: a corner origin is half a cell off the first centre. Row 0 is the top (northmost) row.
  const double x0 = h.x_center ? 0.0 : 0.5, y0 = h.y_center ? 0.0 : 0.5;
  const uint64_t ncols = uint64_t(h.ncols), nrows = uint64_t(h.nrows), total = ncols * nrows;
  auto value_end = [](char c) { return is_space(c); };
  uint64_t k = 0;  // cells read so far
  // Rows are one per line in conforming files; some writers wrap long rows. If the first data line holds
  // exactly one row, every line must, so a short or long row is reported on its own line.
  int row_per_line = -1;  // -1: not known yet
  for (bool more = true; more; more = bool(std::getline(text, line)), line_no += more) {
    const char* p = line.data();
    const char* end = p + line.size();
    uint64_t on_line = 0;
    const uint64_t k_line = k;
    for (;;) {
      while (p < end && is_space(*p)) ++p;
      if (p == end) break;
      if (k == total)
        throw InputError(name, line_no, "more values than ncols x nrows = " + std::to_string(total));
      const char* start = p;
      double v = 0;
      const Parse r = parse_number(p, end, v, value_end);
      if (r != Parse::ok) {
        std::string tok(start, size_t(std::find_if(start, end, is_space) - start));
        throw InputError(
            name, line_no,
            r == Parse::out_of_range ? "number out of range: '" + tok + "'" : "not a number: '" + tok + "'");
      }
      const uint64_t row = k / ncols, col = k % ncols;
      ++k;
      ++on_line;
      if (h.has_nodata && (v == h.nodata || (std::isnan(h.nodata) && std::isnan(v)))) {
        ++in.repairs.nodata_cells;
        continue;
      }
      const double x = h.xll + (double(col) + x0) * h.dx;
      const double y = h.yll + (double(nrows - 1 - row) + y0) * h.dy;
      add_point(in, source, line_no, Point3{x, y, v});
    }
    if (on_line == 0) continue;
    if (row_per_line < 0) row_per_line = on_line == ncols ? 1 : 0;
    if (row_per_line == 1 && on_line != ncols)
      throw InputError(name, line_no,
                       "row " + std::to_string(k_line / ncols + 1) + " has " + std::to_string(on_line) +
                           " values, ncols is " + std::to_string(ncols));
  }
  if (k < total)
    throw InputError(
        name, line_no,
        "expected ncols x nrows = " + std::to_string(total) + " values, found " + std::to_string(k));
  require_geometry(in, before, name);
}

namespace {

// A fault in a grid's data: the sequential reader reads the file again to report it.
struct GridFault {};

// The data of one chunk of grid lines: every value in order, and how many values each line with any holds.
struct GridChunk {
  std::vector<double> z;
  std::vector<std::pair<uint64_t, uint64_t>> lines;  // (line number, values on it)
  uint64_t valid = 0;                                 // values that are not NODATA
};

}  // namespace

void read_ascii_grid_text(std::string_view text, const std::string& name, InputSet& in) {
  auto sequential = [&] {
    std::istringstream s{std::string(text)};
    read_ascii_grid(s, name, in);
  };
  // The header, line by line, up to the first line that starts with a number.
  GridHeader h;
  uint64_t line_no = 0;
  size_t data = text.size();
  for_each_line(text, 0, text.size(), [&](const char* b, const char* e) {
    ++line_no;
    const std::string_view s = trim(std::string_view(b, size_t(e - b)));
    if (s.empty()) return true;
    if (read_header_line(s, line_no, name, h)) return true;
    data = size_t(b - text.data());
    return false;
  });
  if (data == text.size()) return sequential();  // no data: its message
  check_header(h, line_no, name);
  const uint64_t ncols = uint64_t(h.ncols), nrows = uint64_t(h.nrows), total = ncols * nrows;
  auto is_nodata = [&](double v) { return h.has_nodata && (v == h.nodata || (std::isnan(h.nodata) && std::isnan(v))); };

  // Every value of each chunk, on all cores.
  const std::string_view body = text.substr(data);
  const std::vector<Chunk> chunks = split_lines(body, chunk_bytes(body.size()), line_no);
  std::vector<GridChunk> parts(chunks.size());
  try {
    parse_chunks(chunks, [&](size_t k, const Chunk& c) {
      GridChunk& part = parts[k];
      part.z.reserve((c.end - c.begin) / 4);
      uint64_t line = c.first_line;
      for_each_line(body, c.begin, c.end, [&](const char* p, const char* end) {
        const size_t before = part.z.size();
        for (;;) {
          while (p < end && is_space(*p)) ++p;
          if (p == end) break;
          double v = 0;
          if (parse_number(p, end, v, is_space) != Parse::ok) throw GridFault{};
          part.z.push_back(v);
          part.valid += !is_nodata(v);
        }
        if (part.z.size() > before) part.lines.emplace_back(line, part.z.size() - before);
        ++line;
        return true;
      });
    });
  } catch (const GridFault&) {
    return sequential();
  }
  // The counts the sequential reader checks: ncols x nrows values; one row a line if the first line holds one.
  std::vector<uint64_t> first(parts.size() + 1, 0), at(parts.size() + 1, 0);
  int row_per_line = -1;
  for (size_t k = 0; k < parts.size(); ++k) {
    for (const auto& [line, values] : parts[k].lines) {
      if (row_per_line < 0) row_per_line = values == ncols ? 1 : 0;
      if (row_per_line == 1 && values != ncols) return sequential();
    }
    first[k + 1] = first[k] + parts[k].z.size();
    at[k + 1] = at[k] + parts[k].valid;
  }
  if (first.back() != total) return sequential();

  // The vertices, each chunk at its offset, as the sequential reader computes them.
  const uint32_t source = add_source(in, name);
  const size_t base = in.points.size();
  const double x0 = h.x_center ? 0.0 : 0.5, y0 = h.y_center ? 0.0 : 0.5;
  resize_unwritten(in.points, base + at.back());
  std::atomic<bool> bad{false};
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
    Point3* out = in.points.data() + base + at[k];
    uint64_t cell = first[k];
    for (const double v : parts[k].z) {
      const uint64_t row = cell / ncols, col = cell % ncols;
      ++cell;
      if (is_nodata(v)) continue;
      const Point3 q{h.xll + (double(col) + x0) * h.dx, h.yll + (double(nrows - 1 - row) + y0) * h.dy, v};
      try {
        check_finite(in, source, 0, q);
      } catch (const InputError&) {
        bad = true;
        return;
      }
      *out++ = q;
    }
    parts[k] = GridChunk{};
  });
  if (bad) {
    in.points.resize(base);
    in.sources.pop_back();
    return sequential();
  }
  in.repairs.nodata_cells += total - at.back();
  require_geometry(in, base + in.lines.size(), name);
}

}  // namespace cdtgpu
