// Map projection: parses the CRS options, decides whether input is lon/lat, and projects it with
// GeographicLib's Transverse Mercator (Krüger series, about 5 nm accurate) to WGS 84 UTM or GDA94 /
// GDA2020 MGA, which is UTM on the GRS80 ellipsoid. Also writes the ESRI .prj WKT1 for the result.
#include "core/projection.hpp"

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/TransverseMercator.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "core/error.hpp"

namespace cdtgpu {

namespace {

enum class Datum { Wgs84, Gda94, Gda2020 };

constexpr double kGrs80InverseFlattening = 298.257222101;
constexpr double kWgs84InverseFlattening = 298.257223563;

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A whole string as a non-negative int, or -1.
int parse_int(const std::string& s) {
  if (s.empty() || s.size() > 9) return -1;
  int v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || v < 0) return -1;
  return v;
}

struct EpsgInfo {
  Datum datum;
  int zone;
  bool north;
};

// The supported EPSG codes: WGS 84 / UTM (326zz north, 327zz south), GDA94 / MGA zones 48-58 (283zz),
// GDA2020 / MGA zones 46-59 (78zz). MGA is always south.
bool epsg_info(int code, EpsgInfo& info) {
  if (code >= 32601 && code <= 32660) info = {Datum::Wgs84, code - 32600, true};
  else if (code >= 32701 && code <= 32760) info = {Datum::Wgs84, code - 32700, false};
  else if (code >= 28348 && code <= 28358) info = {Datum::Gda94, code - 28300, false};
  else if (code >= 7846 && code <= 7859) info = {Datum::Gda2020, code - 7800, false};
  else return false;
  return true;
}

std::string fmt_number(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, r.ptr);
  // ESRI writes decimals with a point ("500000.0"); keep that look for integral values.
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

int central_meridian(int zone) { return 6 * zone - 183; }

std::string crs_name(Datum datum, int zone, bool north) {
  const std::string z = std::to_string(zone);
  switch (datum) {
    case Datum::Gda94: return "GDA94 / MGA zone " + z;
    case Datum::Gda2020: return "GDA2020 / MGA zone " + z;
    case Datum::Wgs84: break;
  }
  return "WGS 84 / UTM zone " + z + (north ? "N" : "S");
}

// ESRI-style WKT1 of a datum's geographic CRS, as ArcGIS writes it in .prj files (alone or inside a PROJCS).
std::string geogcs_wkt(Datum datum) {
  switch (datum) {
    case Datum::Gda94:
      return "GEOGCS[\"GCS_GDA_1994\",DATUM[\"D_GDA_1994\",SPHEROID[\"GRS_1980\",6378137.0," +
             fmt_number(kGrs80InverseFlattening) + "]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]";
    case Datum::Gda2020:
      return "GEOGCS[\"GCS_GDA2020\",DATUM[\"D_GDA2020\",SPHEROID[\"GRS_1980\",6378137.0," +
             fmt_number(kGrs80InverseFlattening) + "]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]";
    case Datum::Wgs84: break;
  }
  return "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137.0," +
         fmt_number(kWgs84InverseFlattening) + "]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]";
}

// ESRI-style WKT1 as ArcGIS writes it in .prj files.
std::string crs_wkt(Datum datum, int zone, bool north) {
  const std::string z = std::to_string(zone);
  std::string projcs;
  switch (datum) {
    case Datum::Wgs84: projcs = "WGS_1984_UTM_Zone_" + z + (north ? "N" : "S"); break;
    case Datum::Gda94: projcs = "GDA_1994_MGA_Zone_" + z; break;
    case Datum::Gda2020: projcs = "GDA2020_MGA_Zone_" + z; break;
  }
  std::string w = "PROJCS[\"" + projcs + "\"," + geogcs_wkt(datum) + ","
                  "PROJECTION[\"Transverse_Mercator\"],"
                  "PARAMETER[\"False_Easting\",500000.0],"
                  "PARAMETER[\"False_Northing\"," +
                  std::string(north ? "0.0" : "10000000.0") +
                  "],"
                  "PARAMETER[\"Central_Meridian\"," +
                  fmt_number(central_meridian(zone)) +
                  "],"
                  "PARAMETER[\"Scale_Factor\",0.9996],"
                  "PARAMETER[\"Latitude_Of_Origin\",0.0],"
                  "UNIT[\"Meter\",1.0]]";
  return w;
}

Crs make_crs(Datum datum, int zone, bool north) {
  Crs c;
  c.projected = true;
  c.from_geographic = true;
  c.zone = zone;
  c.north = north;
  switch (datum) {
    case Datum::Wgs84: c.epsg = (north ? 32600 : 32700) + zone; break;
    case Datum::Gda94: c.epsg = 28300 + zone; break;
    case Datum::Gda2020: c.epsg = 7800 + zone; break;
  }
  c.name = crs_name(datum, zone, north);
  c.wkt = crs_wkt(datum, zone, north);
  return c;
}

// The datum of a Crs we made, from its EPSG code.
Datum datum_of(const Crs& crs) {
  EpsgInfo info{};
  if (epsg_info(crs.epsg, info)) return info.datum;
  return Datum::Wgs84;
}

// The points' ranges whose bounds a reader gave (InputSet::point_extents), in order; none if any is out of place.
std::vector<InputSet::Extent> known_extents(const InputSet& in) {
  std::vector<InputSet::Extent> e = in.point_extents;
  std::sort(e.begin(), e.end(), [](const auto& a, const auto& b) { return a.begin < b.begin; });
  for (size_t i = 0; i < e.size(); ++i)
    if (e[i].begin > e[i].end || e[i].end > in.points.size() || (i && e[i].begin < e[i - 1].end)) return {};
  return e;
}

// On all cores: 1.25B points took 6.7 s on one (H100 machine). Points whose reader gave their bounds are not read.
Bounds bounds_of(const InputSet& in) {
  using Range = tbb::blocked_range<size_t>;
  auto join = [](Bounds a, const Bounds& b) {
    a.add(b);
    return a;
  };
  auto points_in = [&](size_t from, size_t to) {
    return tbb::parallel_reduce(Range(from, to, 1 << 16), Bounds{}, [&](const Range& r, Bounds acc) {
      for (size_t i = r.begin(); i < r.end(); ++i) acc.add(in.points[i]);
      return acc;
    }, join);
  };
  Bounds b;
  size_t at = 0;
  for (const InputSet::Extent& e : known_extents(in)) {
    if (e.begin > at) b.add(points_in(at, e.begin));
    b.add(e.bounds);
    at = e.end;
  }
  if (in.points.size() > at) b.add(points_in(at, in.points.size()));
  b.add(tbb::parallel_reduce(Range(0, in.lines.size()), Bounds{}, [&](const Range& r, Bounds acc) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      for (const Point3& p : in.lines[i].points) acc.add(p);
    return acc;
  }, join));
  return b;
}

// Longitudes of lon/lat data that crosses the antimeridian (points at 179.9 and -179.9) span almost 360
// degrees and their mean is near 0: the zone picked from it lay half the globe away. The range with negative
// longitudes moved up by 360 is the data's real extent when it is the shorter one.
struct LonRange {
  double min, max;
  bool unwrapped;
};

LonRange lon_range(const InputSet& in, const Bounds& b) {
  LonRange r{b.min_x, b.max_x, false};
  if (b.max_x - b.min_x <= 180) return r;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto add = [&](double x) {
    const double u = x < 0 ? x + 360 : x;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  };
  for (const Point3& p : in.points) add(p.x);
  for (const Polyline& l : in.lines)
    for (const Point3& p : l.points) add(p.x);
  if (hi - lo < b.max_x - b.min_x) r = {lo, hi, true};
  return r;
}

// The .prj of the first shapefile read says the coordinates are geographic (WKT1 GEOGCS, WKT2 GEOGCRS).
bool prj_is_geographic(const std::string& wkt) {
  const std::string w = lower(wkt.substr(0, 8));
  return w.rfind("geogcs[", 0) == 0 || w.rfind("geogcrs[", 0) == 0;
}

// The datum a geographic .prj names: GDA2020 and GDA94 (Australia: projected to MGA), WGS 84 (to UTM). Empty
// text (no .prj) is taken as WGS 84, as the data's lon/lat would be by default; any other datum is an error,
// since projecting it as WGS 84 would be off by up to hundreds of metres.
Datum prj_datum(const std::string& wkt, const std::string& file) {
  if (wkt.empty() || !prj_is_geographic(wkt)) return Datum::Wgs84;
  std::string w = lower(wkt);
  w.erase(std::remove_if(w.begin(), w.end(), [](char c) { return c == '_' || c == ' ' || c == '"'; }), w.end());
  if (w.find("gda2020") != std::string::npos) return Datum::Gda2020;
  if (w.find("gda94") != std::string::npos || w.find("gda1994") != std::string::npos ||
      w.find("geocentricdatumofaustralia1994") != std::string::npos)
    return Datum::Gda94;
  if (w.find("wgs84") != std::string::npos || w.find("wgs1984") != std::string::npos ||
      w.find("worldgeodeticsystem1984") != std::string::npos)
    return Datum::Wgs84;
  throw InputError(file, 0,
                   "its .prj names a geographic datum cdtgpu does not project (GDA2020, GDA94 and WGS 84 are "
                   "known): " + wkt.substr(0, 120) + " (--crs none keeps the coordinates as read)");
}

bool is_lon_lat(const Bounds& b) {
  return !b.empty() && b.min_x >= -180 && b.max_x <= 180 && b.min_y >= -90 && b.max_y <= 90;
}

// The EPSG code of an MGA or UTM .prj (ESRI names such as GDA2020_MGA_Zone_56, GDA_1994_MGA_Zone_55,
// WGS_1984_UTM_Zone_56S), 0 for anything else.
int projected_epsg(const std::string& wkt) {
  std::string w = lower(wkt.substr(0, wkt.find(',')));
  if (w.rfind("projcs[", 0) != 0) return 0;
  w.erase(std::remove_if(w.begin(), w.end(), [](char c) { return c == '_' || c == ' ' || c == '"'; }), w.end());
  const size_t at = w.find("zone");
  if (at == std::string::npos) return 0;
  int zone = 0;
  const char* p = w.data() + at + 4;
  const auto [end, ec] = std::from_chars(p, w.data() + w.size(), zone);
  if (ec != std::errc() || zone < 1 || zone > 60) return 0;
  int code = 0;
  if (w.find("mga") != std::string::npos && w.find("gda2020") != std::string::npos)
    code = 7800 + zone;
  else if (w.find("mga") != std::string::npos && (w.find("gda1994") != std::string::npos || w.find("gda94") != std::string::npos))
    code = 28300 + zone;
  else if (w.find("utm") != std::string::npos && (w.find("wgs1984") != std::string::npos || w.find("wgs84") != std::string::npos))
    code = (end < w.data() + w.size() && *end == 'n' ? 32600 : 32700) + zone;
  EpsgInfo info{};
  return epsg_info(code, info) ? code : 0;
}

// Coordinates kept as read (projected stays false: we did not project). The name comes from the .prj's
// PROJCS/GEOGCS name when there is one.
Crs kept_crs(const InputSet& in, const std::string& fallback_name) {
  Crs c;
  c.wkt = in.source_crs_wkt;
  c.name = fallback_name;
  for (const char* key : {"PROJCS[\"", "GEOGCS[\""}) {
    const size_t at = c.wkt.find(key);
    if (at == std::string::npos) continue;
    const size_t start = at + std::char_traits<char>::length(key);
    const size_t end = c.wkt.find('"', start);
    if (end != std::string::npos && end > start) c.name = c.wkt.substr(start, end - start);
    break;
  }
  c.epsg = projected_epsg(c.wkt);
  return c;
}

}  // namespace

CrsRequest parse_crs(const std::string& text) {
  CrsRequest r;
  const std::string t = lower(text);
  if (t == "auto") return r;
  if (t == "none") {
    r.mode = CrsRequest::Mode::None;
    return r;
  }
  // A UTM zone: digits then N or S.
  if (t.size() >= 2 && (t.back() == 'n' || t.back() == 's') && std::isdigit(static_cast<unsigned char>(t[0]))) {
    const int zone = parse_int(t.substr(0, t.size() - 1));
    if (zone < 1 || zone > 60)
      throw UsageError("UTM zone '" + text + "' out of range: the zone number must be 1 to 60, e.g. 55S");
    r.mode = CrsRequest::Mode::Utm;
    r.zone = zone;
    r.north = t.back() == 'n';
    return r;
  }
  std::string digits = t;
  if (digits.rfind("epsg:", 0) == 0) digits = digits.substr(5);
  const int code = parse_int(digits);
  if (code >= 0) {
    EpsgInfo info{};
    if (!epsg_info(code, info))
      throw UsageError("unsupported EPSG code " + std::to_string(code) +
                       " (supported: 32601-32660 and 32701-32760 WGS 84 / UTM, 28348-28358 GDA94 / MGA, "
                       "7846-7859 GDA2020 / MGA)");
    r.mode = CrsRequest::Mode::Epsg;
    r.epsg = code;
    r.zone = info.zone;
    r.north = info.north;
    return r;
  }
  throw UsageError("unknown CRS '" + text + "' (use auto, none, a UTM zone such as 55S, or EPSG:7855)");
}

Crs choose_crs(const InputSet& in, const CrsRequest& request) {
  using Mode = CrsRequest::Mode;
  if (request.mode == Mode::None) {
    Crs c = kept_crs(in, "none");
    c.name = "none";
    return c;
  }
  const Bounds b = bounds_of(in);
  const bool lon_lat = is_lon_lat(b);
  const std::string extent = "x from " + fmt_number(b.min_x) + " to " + fmt_number(b.max_x) + ", y from " +
                             fmt_number(b.min_y) + " to " + fmt_number(b.max_y);
  // The readers check each shapefile against its own .prj; this catches other inputs read along with a
  // geographic shapefile that are not lon/lat (mixed coordinate systems would be triangulated as one).
  if (!b.empty() && !lon_lat && prj_is_geographic(in.source_crs_wkt))
    throw InputError(in.sources.empty() ? std::string("input") : in.sources.front(), 0,
                     "its .prj says lon/lat (" + kept_crs(in, "").name + ") but the coordinates read are not (" +
                         extent + "): are the inputs in different coordinate systems? (--crs none keeps them as "
                         "read)");
  if (request.mode == Mode::Auto) {
    if (!lon_lat) {
      // Latitude -95 (a typo or a swapped column) used to be taken as projected metres without a word.
      if (!b.empty() && b.min_x >= -180 && b.max_x <= 180 && b.min_y >= -180 && b.max_y <= 180)
        spdlog::warn("coordinates look like lon/lat but some latitude is beyond +-90 ({}): kept as projected "
                     "coordinates; --crs none says that is meant",
                     extent);
      return kept_crs(in, b.empty() ? "none" : "as input (projected)");
    }
    const LonRange lons = lon_range(in, b);
    double lon = (lons.min + lons.max) / 2;
    if (lon >= 180) lon -= 360;
    const double lat = (b.min_y + b.max_y) / 2;
    if (lons.unwrapped)
      spdlog::info("lon/lat data crosses the antimeridian (longitudes {} to {} east): zone chosen for its centre {}",
                   fmt_number(lons.min), fmt_number(lons.max), fmt_number(lon));
    else if (lons.max - lons.min > 180)
      spdlog::warn("lon/lat data spans {} degrees of longitude: no UTM zone suits it, distortion will be large",
                   fmt_number(lons.max - lons.min));
    // Force a UTM zone even near the poles (the standard rule would choose UPS there).
    const int zone = GeographicLib::UTMUPS::StandardZone(lat, lon, GeographicLib::UTMUPS::UTM);
    // GDA data goes to its own MGA zone (EPSG 78zz / 283zz): what Australian users and their other tools
    // expect, on the GRS80 ellipsoid. MGA is defined south of the equator in zones 46-59 (GDA2020), 48-58
    // (GDA94); elsewhere the data is projected to UTM on WGS 84, with a warning.
    const Datum datum = prj_datum(in.source_crs_wkt, in.sources.empty() ? "input" : in.sources.front());
    if (datum != Datum::Wgs84) {
      const int code = (datum == Datum::Gda2020 ? 7800 : 28300) + zone;
      EpsgInfo info{};
      if (lat < 0 && epsg_info(code, info)) return make_crs(datum, zone, false);
      spdlog::warn("{} data outside the MGA zones (zone {}{}): projected to WGS 84 / UTM instead",
                   datum == Datum::Gda2020 ? "GDA2020" : "GDA94", zone, lat >= 0 ? "N" : "S");
    }
    return make_crs(Datum::Wgs84, zone, lat >= 0);
  }
  if (!b.empty() && !lon_lat)
    throw UsageError("a projection was requested but the input is not lon/lat (" + extent +
                     "); use --crs auto or none for projected input");
  if (request.mode == Mode::Utm) {
    if (request.zone < 1 || request.zone > 60) throw UsageError("UTM zone must be 1 to 60");
    return make_crs(Datum::Wgs84, request.zone, request.north);
  }
  EpsgInfo info{};
  if (!epsg_info(request.epsg, info)) throw UsageError("unsupported EPSG code " + std::to_string(request.epsg));
  return make_crs(info.datum, info.zone, info.north);
}

void project(InputSet& in, const Crs& crs) {
  if (!crs.from_geographic) return;
  in.point_extents.clear();  // the readers' bounds were of the coordinates read
  const double a = GeographicLib::Constants::WGS84_a();  // GRS80 has the same equatorial radius
  const double f = datum_of(crs) == Datum::Wgs84 ? 1 / kWgs84InverseFlattening : 1 / kGrs80InverseFlattening;
  const GeographicLib::TransverseMercator tm(a, f, GeographicLib::Constants::UTM_k0());
  const double lon0 = central_meridian(crs.zone);
  const double false_northing = crs.north ? 0 : 10000000;
  auto forward = [&](Point3& p) {
    double x, y;
    tm.Forward(lon0, p.y, p.x, x, y);
    p.x = x + 500000;
    p.y = y + false_northing;
  };
  for (Point3& p : in.points) forward(p);
  for (Polyline& l : in.lines)
    for (Point3& p : l.points) forward(p);
}

bool crs_wkt_is_geographic(const std::string& wkt) { return prj_is_geographic(wkt); }

std::string epsg_wkt(int code) {
  EpsgInfo info{};
  if (epsg_info(code, info)) return crs_wkt(info.datum, info.zone, info.north);
  if (code == 4326) return geogcs_wkt(Datum::Wgs84);
  if (code == 4283) return geogcs_wkt(Datum::Gda94);
  if (code == 7844) return geogcs_wkt(Datum::Gda2020);
  return {};
}

}  // namespace cdtgpu
