// Readers for the LandXML and 2DM meshes that write_landxml / write_2dm produce, so `cdtgpu verify` takes
// them too. Small, line- and tag-based, not general XML: enough for the <Pnts>/<Faces> of one TIN surface
// and the ND/E3T cards of a triangle mesh, with every number parsed exactly by std::from_chars.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "io/mesh_formats.hpp"

namespace cdtgpu {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Whitespace-separated tokens of a string_view.
struct Tokens {
  std::string_view s;
  size_t i = 0;
  std::string_view next() {
    while (i < s.size() && is_space(s[i])) ++i;
    const size_t b = i;
    while (i < s.size() && !is_space(s[i])) ++i;
    return s.substr(b, i - b);
  }
  bool done() {
    while (i < s.size() && is_space(s[i])) ++i;
    return i >= s.size();
  }
};

bool parse(std::string_view t, double& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && ec == std::errc() && p == t.data() + t.size() && std::isfinite(v);
}

bool parse(std::string_view t, uint64_t& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && ec == std::errc() && p == t.data() + t.size();
}

uint64_t line_of(std::string_view text, size_t pos) {
  return uint64_t(std::count(text.begin(), text.begin() + std::min(pos, text.size()), '\n')) + 1;
}

// Ids to vertex indices, in the order the vertices appear.
struct Ids {
  std::unordered_map<uint64_t, uint32_t> index;
  bool add(uint64_t id, uint32_t v) { return index.emplace(id, v).second; }
  bool find(uint64_t id, uint32_t& v) const {
    auto it = index.find(id);
    if (it == index.end()) return false;
    v = it->second;
    return true;
  }
};

// The text of each <tag ...>text</tag> inside [from, to), with the position of its start.
template <class F>
void for_elements(std::string_view text, std::string_view tag, size_t from, size_t to, F&& f) {
  // Built with += : GCC 12 gives a false -Wrestrict warning on "<" + std::string(...) here.
  std::string open = "<", close = "</";
  open += tag;
  close += tag;
  close += '>';
  size_t pos = from;
  while ((pos = text.find(open, pos)) != std::string_view::npos && pos < to) {
    const size_t after = pos + open.size();
    if (after >= text.size() || (text[after] != '>' && !is_space(text[after]))) {
      pos = after;
      continue;
    }
    const size_t gt = text.find('>', after);
    const size_t end = gt == std::string_view::npos ? gt : text.find(close, gt);
    if (end == std::string_view::npos) throw std::runtime_error("unterminated <" + std::string(tag) + ">");
    f(text.substr(pos + 1, gt - pos - 1), text.substr(gt + 1, end - gt - 1), pos);
    pos = end + close.size();
  }
}

}  // namespace

Mesh read_landxml(const std::string& path, std::string_view text) {
  Mesh mesh;
  const size_t pnts = text.find("<Pnts");
  if (pnts == std::string_view::npos)
    throw InputError(path, 0, "no <Pnts> element (not a LandXML TIN surface)");
  const size_t pnts_end = text.find("</Pnts>", pnts);
  if (pnts_end == std::string_view::npos) throw InputError(path, line_of(text, pnts), "<Pnts> is not closed");
  Ids ids;
  try {
    for_elements(text, "P", pnts, pnts_end, [&](std::string_view head, std::string_view body, size_t at) {
      const size_t q = head.find("id=\"");
      uint64_t id = 0;
      const size_t qe = q == std::string_view::npos ? q : head.find('"', q + 4);
      if (qe == std::string_view::npos || !parse(head.substr(q + 4, qe - q - 4), id))
        throw InputError(path, line_of(text, at), "<P> without a numeric id");
      Tokens tk{body};
      double n = 0, e = 0, z = 0;
      if (!parse(tk.next(), n) || !parse(tk.next(), e) || !parse(tk.next(), z) || !tk.done())
        throw InputError(path, line_of(text, at),
                         "<P> must hold three finite numbers: northing easting elevation");
      if (!ids.add(id, uint32_t(mesh.vertices.size())))
        throw InputError(path, line_of(text, at), "point id " + std::to_string(id) + " given twice");
      mesh.vertices.push_back({e, n, z});
    });
    const size_t faces = text.find("<Faces", pnts_end);
    if (faces == std::string_view::npos) return mesh;
    const size_t faces_end = text.find("</Faces>", faces);
    if (faces_end == std::string_view::npos)
      throw InputError(path, line_of(text, faces), "<Faces> is not closed");
    for_elements(text, "F", faces, faces_end, [&](std::string_view, std::string_view body, size_t at) {
      Tokens tk{body};
      Triangle tri{};
      for (uint32_t& v : tri) {
        uint64_t id = 0;
        if (!parse(tk.next(), id)) throw InputError(path, line_of(text, at), "<F> must hold three point ids");
        if (!ids.find(id, v))
          throw InputError(path, line_of(text, at),
                           "<F> names point id " + std::to_string(id) + ", which is not in <Pnts>");
      }
      if (!tk.done()) throw InputError(path, line_of(text, at), "<F> must hold three point ids");
      mesh.triangles.push_back(tri);
    });
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw InputError(path, 0, e.what());
  }
  return mesh;
}

Mesh read_2dm(const std::string& path, std::string_view text) {
  Mesh mesh;
  Ids ids;
  struct Face {
    uint64_t id[3];
    uint64_t line;
  };
  std::vector<Face> faces;  // elements may come before the nodes they name
  uint64_t line_no = 0;
  size_t pos = 0;
  bool header = false;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    Tokens tk{line};
    const std::string_view card = tk.next();
    if (card.empty()) continue;
    if (!header) {
      if (card != "MESH2D") throw InputError(path, line_no, "a 2DM mesh starts with MESH2D");
      header = true;
      continue;
    }
    if (card == "ND") {
      uint64_t id = 0;
      double x = 0, y = 0, z = 0;
      if (!parse(tk.next(), id) || !parse(tk.next(), x) || !parse(tk.next(), y) || !parse(tk.next(), z))
        throw InputError(path, line_no, "ND must be followed by id x y z");
      if (!ids.add(id, uint32_t(mesh.vertices.size())))
        throw InputError(path, line_no, "node id " + std::to_string(id) + " given twice");
      mesh.vertices.push_back({x, y, z});
    } else if (card == "E3T") {
      Face f{{}, line_no};
      uint64_t id = 0;
      if (!parse(tk.next(), id) || !parse(tk.next(), f.id[0]) || !parse(tk.next(), f.id[1]) ||
          !parse(tk.next(), f.id[2]))
        throw InputError(path, line_no, "E3T must be followed by id n1 n2 n3");
      faces.push_back(f);
    } else if (card[0] == 'E' && card.size() == 3 && card != "E2L") {
      throw InputError(path, line_no,
                       "element " + std::string(card) + " is not a triangle (only E3T is read)");
    }
  }
  if (!header) throw InputError(path, 0, "empty file (a 2DM mesh starts with MESH2D)");
  for (const Face& f : faces) {
    Triangle tri{};
    for (int k = 0; k < 3; ++k)
      if (!ids.find(f.id[k], tri[k]))
        throw InputError(path, f.line,
                         "E3T names node " + std::to_string(f.id[k]) + ", which has no ND card");
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

}  // namespace cdtgpu
