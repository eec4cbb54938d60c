// read_peer_input: the text format of artem-ogre/CDT's test inputs (../shared/data/cdt-peer-inputs):
// "V E", then V lines "x y" (z = 0), then E lines "i j" of 0-based vertex indices, each a constraint edge.
// Blank lines are skipped; '\r' counts as white space, so CRLF files read the same.
#include <charconv>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/repair.hpp"
#include "io/readers.hpp"

namespace cdtgpu {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// Splits a line into exactly two numbers of type T; false if it has another shape.
template <typename T>
bool two_numbers(const std::string& line, T& a, T& b) {
  const char* p = line.data();
  const char* end = p + line.size();
  T* out[2] = {&a, &b};
  for (T* v : out) {
    while (p < end && is_space(*p)) ++p;
    if (p < end && *p == '+') ++p;
    auto [q, ec] = std::from_chars(p, end, *v);
    if (ec != std::errc() || (q < end && !is_space(*q))) return false;
    p = q;
  }
  while (p < end && is_space(*p)) ++p;
  return p == end;
}

bool blank(const std::string& line) {
  for (char c : line)
    if (!is_space(c)) return false;
  return true;
}

}  // namespace

void read_peer_input(std::istream& text, const std::string& name, InputSet& in) {
  in.sources.push_back(name);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  std::string line;
  uint64_t line_no = 0;
  auto next_line = [&]() {
    while (std::getline(text, line)) {
      ++line_no;
      if (!blank(line)) return true;
    }
    return false;
  };

  uint64_t nv = 0, ne = 0;
  if (!next_line()) throw InputError(name, 0, "empty file (expected a first line \"V E\")");
  if (!two_numbers(line, nv, ne)) throw InputError(name, line_no, "expected \"V E\" (two counts)");

  Points vertices;
  vertices.reserve(nv < (1u << 24) ? nv : (1u << 24));
  for (uint64_t i = 0; i < nv; ++i) {
    if (!next_line())
      throw InputError(name, line_no,
                       "file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    double x = 0, y = 0;
    if (!two_numbers(line, x, y)) throw InputError(name, line_no, "expected a vertex \"x y\"");
    const Point3 p{x, y, 0.0};
    check_finite(in, source, line_no, p);
    vertices.push_back(p);
    // Every vertex is a point of the triangulation, whether or not an edge uses it.
    in.points.push_back(p);
  }
  for (uint64_t k = 0; k < ne; ++k) {
    if (!next_line())
      throw InputError(name, line_no,
                       "file ends after " + std::to_string(k) + " of " + std::to_string(ne) + " edges");
    uint64_t i = 0, j = 0;
    if (!two_numbers(line, i, j))
      throw InputError(name, line_no, "expected an edge \"i j\" (two vertex indices)");
    if (i >= nv || j >= nv)
      throw InputError(name, line_no,
                       "vertex index " + std::to_string(i >= nv ? i : j) + " out of range (" +
                           std::to_string(nv) + " vertices)");
    Polyline l;
    l.points = {vertices[i], vertices[j]};
    l.source = source;
    l.record = line_no;
    add_polyline(in, std::move(l));
  }
  if (next_line())
    throw InputError(name, line_no, "unexpected line after the " + std::to_string(ne) + " edges");
}

}  // namespace cdtgpu
