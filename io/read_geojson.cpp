// GeoJSON reader over nlohmann/json's document model (a dependency already: the stats and the tiles' index).
// The checks are ours: nlohmann parses any JSON, and GeoJSON's rules (types, position arrays, ring sizes,
// lon/lat ranges) are checked here with the feature number in every message.
#include "io/read_geojson.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "core/repair.hpp"

namespace cdtgpu {

namespace {

using json = nlohmann::json;

std::string kind_of(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    case json::value_t::string: return "a string";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::discarded: return "nothing";
    default: return "a number";
  }
}

// "[json.exception.parse_error.101] parse error at line 2, column 5: ..." without the bracketed prefix.
std::string json_message(const json::exception& e) {
  std::string s = e.what();
  if (!s.empty() && s.front() == '[') {
    const size_t end = s.find("] ");
    if (end != std::string::npos) s.erase(0, end + 2);
  }
  return s;
}

// The CRS a legacy "crs" member names: {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::7856"}}
// (also "EPSG:7856", ".../def/crs/EPSG/0/7856", OGC CRS84) or {"type": "EPSG", "properties": {"code": 7856}}.
// Returns the EPSG code, 4326 for CRS84.
int crs_member_code(const json& crs, const std::string& name) {
  auto fail = [&](const std::string& what) { throw InputError(name, 0, "the \"crs\" member " + what); };
  if (!crs.is_object()) fail("is " + kind_of(crs) + ", not an object");
  const auto type = crs.find("type");
  const auto props = crs.find("properties");
  if (type == crs.end() || !type->is_string() || props == crs.end() || !props->is_object())
    fail("needs a \"type\" string and a \"properties\" object");
  if (*type == "EPSG") {
    const auto code = props->find("code");
    if (code == props->end() || !code->is_number_integer() || code->get<int64_t>() <= 0 ||
        code->get<int64_t>() > 1000000)
      fail("of type EPSG needs an integer \"code\"");
    return int(code->get<int64_t>());
  }
  if (*type != "name") fail("of type " + type->dump() + " is not supported (name or EPSG)");
  const auto text = props->find("name");
  if (text == props->end() || !text->is_string()) fail("of type name needs a \"name\" string");
  std::string s = text->get<std::string>();
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (s.find("CRS84") != std::string::npos) return 4326;
  size_t digits = s.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(s[digits - 1]))) --digits;
  int code = 0;
  if (s.find("EPSG") == std::string::npos || digits == s.size() || s.size() - digits > 6 ||
      std::from_chars(s.data() + digits, s.data() + s.size(), code).ec != std::errc() || code == 0)
    fail("names '" + text->get<std::string>() + "', not an EPSG code (e.g. urn:ogc:def:crs:EPSG::7856)");
  return code;
}

// Where in a geometry a problem is: "MultiPolygon polygon 2, ring 1, position 4".
struct Where {
  const std::string* type;
  size_t part = 0, ring = 0, position = 0;  // 1-based; 0: not applicable
  std::string text() const {
    std::string s = *type;
    const char* part_name = *type == "MultiPolygon" ? "polygon" : *type == "MultiPoint" ? "point" : "line";
    if (part) s += std::string(" ") + part_name + " " + std::to_string(part);
    if (ring) s += std::string(part ? "," : "") + " ring " + std::to_string(ring);
    if (position) s += std::string(part || ring ? "," : "") + " position " + std::to_string(position);
    return s;
  }
};

class Reader {
 public:
  Reader(const std::string& name, const std::string& z_property, uint32_t source, InputSet& in)
      : name_(name), z_property_(z_property), source_(source), in_(in) {}

  void document(const json& doc) {
    if (!doc.is_object()) throw InputError(name_, 0, "not GeoJSON: the top level is " + kind_of(doc) + ", not an object");
    set_crs(doc);
    const std::string& type = type_of(doc, "the top-level object");
    if (type == "FeatureCollection") {
      const auto features = doc.find("features");
      if (features == doc.end() || !features->is_array())
        throw InputError(name_, 0, "the FeatureCollection has no \"features\" array");
      for (const json& f : *features) {
        ++feature_;
        if (!f.is_object() || type_of(f, "a feature") != "Feature")
          fail("expected a Feature, found " + (f.is_object() ? "a " + type_of(f, "") : kind_of(f)));
        read_feature(f);
      }
    } else if (type == "Feature") {
      feature_ = 1;
      read_feature(doc);
    } else {
      feature_ = 1;
      if (!z_property_.empty())
        fail("z=" + z_property_ + " names a feature property, and this file is a bare " + type +
             " without properties");
      geometry(doc, 0);
    }
    const bool looks_lon_lat =
        points_ > 0 && bounds_[0] >= -180 && bounds_[1] <= 180 && bounds_[2] >= -90 && bounds_[3] <= 90;
    const std::string extent = "x " + number_text(bounds_[0]) + " to " + number_text(bounds_[1]) + ", y " +
                               number_text(bounds_[2]) + " to " + number_text(bounds_[3]);
    if (!has_crs_ && (looks_lon_lat || points_ == 0)) {
      if (in_.source_crs_wkt.empty()) in_.source_crs_wkt = epsg_wkt(4326);
    } else if (!has_crs_) {
      // GDAL writes no crs member for a layer without a CRS, and so does cdtgpu's --contours-out: read as the
      // coordinates of an unnamed projected CRS, which is what they are, rather than refused.
      spdlog::warn("{}: coordinates are not longitude/latitude ({}), which GeoJSON without a \"crs\" member is "
                   "(RFC 7946): kept as read, in an unnamed projected CRS",
                   name_, extent);
    }
    if (unknown_code_ && looks_lon_lat)
      throw InputError(name_, 0,
                       "its \"crs\" member names EPSG:" + std::to_string(code_) +
                           ", which cdtgpu does not know, and its coordinates look like longitude/latitude: the "
                           "datum cannot be told (known: 4326, 4283, 7844 and the MGA / UTM codes of --epsg)");
    if (unknown_code_)
      spdlog::warn("{}: its \"crs\" member names EPSG:{}, which cdtgpu does not know: coordinates kept as read",
                   name_, code_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(name_, 0, (feature_ ? "feature " + std::to_string(feature_) + ": " : std::string()) + what);
  }
  [[noreturn]] void fail(const Where& w, const std::string& what) const { fail(w.text() + ": " + what); }

  const std::string& type_of(const json& o, const std::string& what) {
    const auto t = o.find("type");
    if (t == o.end()) fail(what + " has no \"type\"");
    if (!t->is_string()) fail(what + "'s \"type\" is " + kind_of(*t) + ", not a string");
    return t->get_ref<const std::string&>();
  }

  // RFC 7946 GeoJSON is lon/lat on WGS 84; a legacy crs member may say otherwise.
  void set_crs(const json& doc) {
    const auto crs = doc.find("crs");
    has_crs_ = crs != doc.end() && !crs->is_null();
    if (!has_crs_) return;  // lon/lat unless the coordinates say otherwise (document() decides)
    code_ = crs_member_code(*crs, name_);
    const std::string wkt = epsg_wkt(code_);
    unknown_code_ = wkt.empty();
    lon_lat_ = crs_wkt_is_geographic(wkt);
    if (in_.source_crs_wkt.empty()) in_.source_crs_wkt = wkt;
  }

  void read_feature(const json& f) {
    const auto props = f.find("properties");
    if (props != f.end() && !props->is_null() && !props->is_object())
      fail("\"properties\" is " + kind_of(*props) + ", not an object");
    const auto g = f.find("geometry");
    if (g == f.end()) fail("the Feature has no \"geometry\" member (null for none)");
    if (g->is_null()) {
      ++in_.repairs.null_shapes;
      return;
    }
    z_ = std::nullopt;
    if (!z_property_.empty()) z_ = z_from(props == f.end() ? json() : *props);
    geometry(*g, 0);
  }

  // The z property of a feature: a number, or a string holding one (CSV conversions write numbers as text).
  double z_from(const json& props) const {
    const json* value = nullptr;
    std::string names;
    if (props.is_object()) {
      const auto exact = props.find(z_property_);
      if (exact != props.end()) value = &*exact;
      for (auto it = props.begin(); it != props.end(); ++it) {
        names += (names.empty() ? "" : ", ") + it.key();
        if (!value && it.key().size() == z_property_.size() &&
            std::equal(it.key().begin(), it.key().end(), z_property_.begin(),
                       [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) ==
                                                   std::tolower(static_cast<unsigned char>(b)); }))
          value = &it.value();
      }
    }
    if (!value)
      fail("no property " + z_property_ + " for z (properties: " + (names.empty() ? "none" : names) + ")");
    if (value->is_number()) {
      const double z = value->get<double>();
      if (!std::isfinite(z)) fail("property " + z_property_ + " is not a finite number");
      return z;
    }
    if (value->is_string()) {
      const std::string& s = value->get_ref<const std::string&>();
      std::string_view t(s);
      while (!t.empty() && std::isspace(static_cast<unsigned char>(t.front()))) t.remove_prefix(1);
      while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.remove_suffix(1);
      if (!t.empty() && t.front() == '+') t.remove_prefix(1);
      double z = 0;
      const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), z);
      if (ec == std::errc() && end == t.data() + t.size() && !t.empty() && std::isfinite(z)) return z;
      fail("property " + z_property_ + " is '" + s + "', not a number");
    }
    fail("property " + z_property_ + " is " + kind_of(*value) + ", not a number");
  }

  Point3 position(const json& p, const Where& w) {
    if (!p.is_array()) fail(w, "expected a position (an array of numbers), found " + kind_of(p));
    if (p.size() < 2) fail(w, "a position needs at least 2 numbers, found " + std::to_string(p.size()));
    double v[3] = {0, 0, 0};
    const size_t n = std::min<size_t>(p.size(), 3);
    for (size_t k = 0; k < p.size(); ++k) {
      if (!p[k].is_number()) fail(w, "number " + std::to_string(k + 1) + " is " + kind_of(p[k]));
      if (k < n) v[k] = p[k].get<double>();
    }
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      fail(w, "coordinate is not a finite number");
    if (std::abs(v[0]) > kMaxCoordinate || std::abs(v[1]) > kMaxCoordinate)
      fail(w, "coordinate beyond ±1e15, far outside any coordinate reference system");
    if (lon_lat_ && !(v[0] >= -180 && v[0] <= 180 && v[1] >= -90 && v[1] <= 90))
      fail(w, "(" + number_text(v[0]) + " " + number_text(v[1]) + ") is not a longitude/latitude, and the \"crs\" "
                  "member names the geographic EPSG:" + std::to_string(code_));
    bounds_[0] = std::min(bounds_[0], v[0]), bounds_[1] = std::max(bounds_[1], v[0]);
    bounds_[2] = std::min(bounds_[2], v[1]), bounds_[3] = std::max(bounds_[3], v[1]);
    ++points_;
    const double z = z_ ? *z_ : n == 3 ? v[2] : in_.nan_for_missing_z ? missing_z() : 0.0;
    return {v[0], v[1], z};
  }

  const json& array_of(const json& a, const Where& w, const char* what) {
    if (!a.is_array()) fail(w, std::string("expected ") + what + " (an array), found " + kind_of(a));
    return a;
  }

  // A LineString's positions (at least 2) or a ring's (at least 4, closed or closed here and counted).
  void line(const json& a, Where w, bool closed) {
    array_of(a, w, closed ? "a ring" : "a line");
    const size_t need = closed ? 4 : 2;
    if (a.size() < need)
      fail(w, std::string(closed ? "a linear ring" : "a LineString") + " needs at least " + std::to_string(need) +
                  " positions, found " + std::to_string(a.size()));
    Polyline l;
    l.closed = closed;
    l.source = source_;
    l.record = feature_;
    l.points.reserve(a.size());
    for (size_t k = 0; k < a.size(); ++k) {
      w.position = k + 1;
      l.points.push_back(position(a[k], w));
    }
    add_polyline(in_, std::move(l));
  }

  void polygon(const json& a, Where w) {
    array_of(a, w, "a polygon's rings");
    for (size_t r = 0; r < a.size(); ++r) {
      w.ring = r + 1;
      line(a[r], w, true);
    }
  }

  void geometry(const json& g, int depth) {
    if (!g.is_object()) fail("expected a geometry object, found " + kind_of(g));
    const std::string& type = type_of(g, "the geometry");
    if (type == "GeometryCollection") {
      if (depth >= 32) fail("GeometryCollections nested too deeply");
      const auto parts = g.find("geometries");
      if (parts == g.end() || !parts->is_array()) fail("the GeometryCollection has no \"geometries\" array");
      for (const json& part : *parts) geometry(part, depth + 1);
      return;
    }
    static const std::string kTypes[] = {"Point", "MultiPoint", "LineString", "MultiLineString", "Polygon",
                                         "MultiPolygon"};
    if (std::find(std::begin(kTypes), std::end(kTypes), type) == std::end(kTypes))
      fail("unknown geometry type '" + type +
           "' (GeoJSON has Point, MultiPoint, LineString, MultiLineString, Polygon, MultiPolygon, "
           "GeometryCollection)");
    const auto c = g.find("coordinates");
    if (c == g.end()) fail(type + " has no \"coordinates\"");
    Where w{&type};
    array_of(*c, w, "coordinates");
    if (c->empty()) {  // an empty geometry (RFC 7946 3.1: may be read as null)
      ++in_.repairs.null_shapes;
      return;
    }
    if (type == "Point") {
      add_point(in_, source_, feature_, position(*c, w));
    } else if (type == "LineString") {
      line(*c, w, false);
    } else if (type == "Polygon") {
      polygon(*c, w);
    } else {
      for (size_t k = 0; k < c->size(); ++k) {
        w.part = k + 1;
        if (type == "MultiPoint")
          add_point(in_, source_, feature_, position((*c)[k], w));
        else if (type == "MultiLineString")
          line((*c)[k], w, false);
        else
          polygon((*c)[k], w);
      }
    }
  }

  const std::string& name_;
  const std::string& z_property_;
  uint32_t source_;
  InputSet& in_;
  uint64_t feature_ = 0;      // 1-based, 0 outside features
  std::optional<double> z_;   // the current feature's z property
  bool has_crs_ = false;
  bool lon_lat_ = false;      // the crs member names a geographic CRS: positions must be lon/lat
  bool unknown_code_ = false;
  int code_ = 0;
  double bounds_[4] = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                       std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  uint64_t points_ = 0;
};

}  // namespace

void read_geojson_text(std::string_view text, const std::string& name, const std::string& z_property,
                       InputSet& in) {
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    throw InputError(name, 0, "not valid JSON: " + json_message(e));
  }
  in.sources.push_back(name);
  const uint32_t source = uint32_t(in.sources.size() - 1);
  const size_t before = in.points.size() + in.lines.size();
  Reader(name, z_property, source, in).document(doc);
  if (in.points.size() + in.lines.size() == before) throw InputError(name, 0, "no geometry");
}

}  // namespace cdtgpu
