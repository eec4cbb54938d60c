// GeoJSON reader (RFC 7946): a FeatureCollection, a Feature or a bare geometry (GeometryCollection included).
// Point and MultiPoint give loose vertices, LineString and MultiLineString open constraint lines, Polygon and
// MultiPolygon closed rings (holes too), as the WKT reader does; z from the third number of each position, or
// from a feature property (z=ELEV on the command line), else missing.
//
//   InputSet in;
//   read_geojson_text(R"({"type":"Point","coordinates":[151.2,-33.9,12]})", "p.geojson", "", in);
//
// Coordinates are longitude and latitude on WGS 84 (RFC 7946), unless a legacy "crs" member (GeoJSON 2008)
// names another CRS by EPSG code ("urn:ogc:def:crs:EPSG::7856", "EPSG:7856"): a projected one cdtgpu knows is
// recorded like a .prj and its coordinates kept, a geographic one gives its datum (positions outside lon/lat
// ranges are errors), an unknown projected one is kept as read (an unknown code whose coordinates look like
// lon/lat is an error: the datum cannot be told). Without a crs member, coordinates outside lon/lat ranges
// (GDAL's GeoJSON of a layer without a CRS, cdtgpu's own --contours-out of one) are kept as read, with a
// warning.
#pragma once
#include <string>
#include <string_view>

#include "core/model.hpp"

namespace cdtgpu {

// z_property: the feature property giving z (empty: z from the positions). Throws InputError naming the file
// and the feature (1-based) for malformed JSON (with its line and column), wrong types, too few positions,
// NaN or infinite numbers, unknown geometry types, or positions that are not lon/lat under a geographic crs.
void read_geojson_text(std::string_view text, const std::string& name, const std::string& z_property,
                       InputSet& in);

}  // namespace cdtgpu
