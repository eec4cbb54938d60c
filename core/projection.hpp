// Map projection with GeographicLib: lon/lat input to UTM / MGA metres.
#pragma once
#include <string>

#include "core/model.hpp"

namespace cdtgpu {

struct CrsRequest {
  enum class Mode { Auto, None, Utm, Epsg } mode = Mode::Auto;
  int zone = 0;        // Utm: 1..60
  bool north = false;  // Utm
  int epsg = 0;        // Epsg: 326xx / 327xx (WGS 84 / UTM), 283xx (GDA94 / MGA), 78xx (GDA2020 / MGA)
};

// Parses "auto", "none", a UTM zone such as "55S", or "EPSG:28355" / "28355". Throws UsageError.
CrsRequest parse_crs(const std::string& text);

struct Crs {
  bool projected = false;    // false: coordinates kept as read
  bool from_geographic = false;  // true: input was lon/lat and was projected
  int epsg = 0;              // 0 when unknown / none
  int zone = 0;
  bool north = false;
  std::string name;          // e.g. "GDA2020 / MGA zone 55", "WGS 84 / UTM zone 55S", "none"
  std::string wkt;           // ESRI .prj style WKT1, empty when unknown
};

// Auto: input whose x in [-180, 180] and y in [-90, 90] is lon/lat and goes to the WGS 84 UTM zone of the
// data's centre; anything else is kept (and its .prj WKT, if any, recorded). Throws UsageError when a
// projection is requested for input that is not lon/lat.
Crs choose_crs(const InputSet& in, const CrsRequest& request);

// The ESRI .prj WKT1 of an EPSG code cdtgpu knows: the projected codes --epsg takes and the geographic 4326
// (WGS 84), 4283 (GDA94) and 7844 (GDA2020); empty for any other. For files that name their CRS by a code (a
// GeoJSON crs member, LAS and GeoTIFF GeoKeys), recorded in InputSet::source_crs_wkt as a .prj would be.
std::string epsg_wkt(int code);

// A .prj's WKT (WKT1 GEOGCS, WKT2 GEOGCRS) says the coordinates are longitude and latitude in degrees.
bool crs_wkt_is_geographic(const std::string& wkt);

// Projects every point and polyline vertex in place when crs.from_geographic.
void project(InputSet& in, const Crs& crs);

}  // namespace cdtgpu
