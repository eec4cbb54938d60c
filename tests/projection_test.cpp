// Projection: CRS parsing, the Auto choice (lon/lat detection, zone from the data's centre), and projected
// coordinates against published values (GeographicLib's GeoConvert documentation; the GDA Technical Manual's
// worked examples for Flinders Peak and Buninyong, Victoria, MGA zones 54 and 55).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/projection.hpp"

namespace cdtgpu {
namespace {

double dms(int d, int m, double s) { return d + m / 60.0 + s / 3600.0; }

InputSet lon_lat_points(std::initializer_list<std::pair<double, double>> lon_lat) {
  InputSet in;
  for (auto [lon, lat] : lon_lat) in.points.push_back({lon, lat, 100});
  return in;
}

// Projects one lon/lat point with the CRS that `request` gives for it.
Point3 project_one(const std::string& request, double lon, double lat, Crs* out_crs = nullptr) {
  InputSet in = lon_lat_points({{lon, lat}});
  const Crs crs = choose_crs(in, parse_crs(request));
  project(in, crs);
  if (out_crs) *out_crs = crs;
  return in.points[0];
}

TEST(ParseCrs, AcceptsModesZonesAndEpsgCodes) {
  EXPECT_EQ(parse_crs("auto").mode, CrsRequest::Mode::Auto);
  EXPECT_EQ(parse_crs("AUTO").mode, CrsRequest::Mode::Auto);
  EXPECT_EQ(parse_crs("none").mode, CrsRequest::Mode::None);

  for (const char* s : {"55S", "55s"}) {
    const CrsRequest r = parse_crs(s);
    EXPECT_EQ(r.mode, CrsRequest::Mode::Utm) << s;
    EXPECT_EQ(r.zone, 55) << s;
    EXPECT_FALSE(r.north) << s;
  }
  const CrsRequest n = parse_crs("1N");
  EXPECT_EQ(n.zone, 1);
  EXPECT_TRUE(n.north);
  EXPECT_EQ(parse_crs("60s").zone, 60);

  for (const char* s : {"EPSG:28355", "28355", "epsg:28355"}) {
    const CrsRequest r = parse_crs(s);
    EXPECT_EQ(r.mode, CrsRequest::Mode::Epsg) << s;
    EXPECT_EQ(r.epsg, 28355) << s;
    EXPECT_EQ(r.zone, 55) << s;
  }
  EXPECT_EQ(parse_crs("epsg:7855").epsg, 7855);
  EXPECT_EQ(parse_crs("32755").zone, 55);
  EXPECT_TRUE(parse_crs("EPSG:32633").north);
}

TEST(ParseCrs, RejectsBadStrings) {
  for (const char* s : {"", "utm", "61S", "0N", "55X", "55", "S55", "EPSG:", "EPSG:4326", "EPSG:28360", "7860",
                        "32661", "EPSG:-28355", "55.5S", "auto2"}) {
    EXPECT_THROW(parse_crs(s), UsageError) << "'" << s << "'";
  }
  try {
    parse_crs("61S");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("1 to 60"), std::string::npos) << e.what();
  }
  try {
    parse_crs("EPSG:4326");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("4326"), std::string::npos) << e.what();
  }
}

TEST(Projection, GeoConvertDocumentedExampleBaghdad) {
  // GeoConvert documentation: 33.3N 44.4E is "38n 444140.54 3684706.36".
  Crs crs;
  const Point3 p = project_one("auto", 44.4, 33.3, &crs);
  EXPECT_EQ(crs.zone, 38);
  EXPECT_TRUE(crs.north);
  EXPECT_EQ(crs.epsg, 32638);
  EXPECT_EQ(crs.name, "WGS 84 / UTM zone 38N");
  EXPECT_NEAR(p.x, 444140.54, 0.005);
  EXPECT_NEAR(p.y, 3684706.36, 0.005);
  EXPECT_EQ(p.z, 100);
}

TEST(Projection, FlindersPeakMatchesPublishedMgaZone55) {
  // GDA Technical Manual: Flinders Peak 37°57'03.72030"S 144°25'29.52440"E is MGA zone 55
  // E 273741.297 N 5796489.777 (GDA94 and GDA2020 share GRS80 and the projection).
  const double lat = -dms(37, 57, 3.72030), lon = dms(144, 25, 29.52440);
  for (const char* epsg : {"EPSG:28355", "EPSG:7855"}) {
    Crs crs;
    const Point3 p = project_one(epsg, lon, lat, &crs);
    EXPECT_NEAR(p.x, 273741.297, 0.001) << epsg;
    EXPECT_NEAR(p.y, 5796489.777, 0.001) << epsg;
    EXPECT_TRUE(crs.from_geographic);
    EXPECT_EQ(crs.zone, 55);
  }
  Crs crs;
  project_one("EPSG:7855", lon, lat, &crs);
  EXPECT_EQ(crs.name, "GDA2020 / MGA zone 55");
  EXPECT_EQ(crs.epsg, 7855);
  project_one("28355", lon, lat, &crs);
  EXPECT_EQ(crs.name, "GDA94 / MGA zone 55");
}

TEST(Projection, BuninyongInZones55And54) {
  // GDA Technical Manual: Buninyong 37°39'10.15610"S 143°55'35.38390"E; zone 55 E 228854.051 N 5828259.038,
  // zone 54 E 758173.797 N 5828674.340 (a point just west of the zone 55 boundary, in both zones).
  const double lat = -dms(37, 39, 10.15610), lon = dms(143, 55, 35.38390);
  const Point3 a = project_one("EPSG:28355", lon, lat);
  EXPECT_NEAR(a.x, 228854.051, 0.001);
  EXPECT_NEAR(a.y, 5828259.038, 0.001);
  const Point3 b = project_one("EPSG:28354", lon, lat);
  EXPECT_NEAR(b.x, 758173.797, 0.001);
  EXPECT_NEAR(b.y, 5828674.340, 0.001);
}

TEST(Projection, Grs80AndWgs84DifferBySubMillimetre) {
  // Canberra, zone 55: the ellipsoids differ only in flattening (by about 1e-13), so MGA and WGS 84 UTM agree
  // to well under a millimetre, but not bit for bit.
  const Point3 mga = project_one("EPSG:7855", 149.1300, -35.2809);
  const Point3 utm = project_one("55S", 149.1300, -35.2809);
  EXPECT_LT(std::abs(mga.x - utm.x), 1e-3);
  EXPECT_LT(std::abs(mga.y - utm.y), 1e-3);
  EXPECT_TRUE(mga.x != utm.x || mga.y != utm.y);
}

TEST(Projection, SouthernHemisphereFalseNorthing) {
  // On the central meridian at the equator the projection gives (0, 0): UTM south adds 500000 / 10000000.
  const Point3 s = project_one("55S", 147, 0);
  EXPECT_EQ(s.x, 500000);
  EXPECT_EQ(s.y, 10000000);
  const Point3 n = project_one("55N", 147, 0);
  EXPECT_EQ(n.x, 500000);
  EXPECT_EQ(n.y, 0);
  // 0.01 degree south of the equator: 1105.74 m of meridian arc, times the scale 0.9996.
  const Point3 p = project_one("55S", 147, -0.01);
  EXPECT_NEAR(p.y, 10000000 - 1105.3, 0.5);
}

TEST(ChooseCrs, AutoPicksZoneOfTheBoundingBoxCentre) {
  // Katoomba NSW (150.31E 33.71S): zone 56 starts at 150E.
  InputSet katoomba = lon_lat_points({{150.30, -33.70}, {150.32, -33.72}});
  Crs crs = choose_crs(katoomba, parse_crs("auto"));
  EXPECT_EQ(crs.zone, 56);
  EXPECT_FALSE(crs.north);
  EXPECT_EQ(crs.epsg, 32756);
  EXPECT_EQ(crs.name, "WGS 84 / UTM zone 56S");

  // Points spread from zone 54 to zone 56; the centre (147E) is in zone 55. A polyline counts too.
  InputSet spread = lon_lat_points({{143.5, -37.0}});
  spread.lines.push_back({{{150.5, -35.0, 0}, {150.4, -35.1, 0}}, false, 0, 1});
  crs = choose_crs(spread, parse_crs("auto"));
  EXPECT_EQ(crs.zone, 55);
  EXPECT_EQ(crs.epsg, 32755);
  EXPECT_TRUE(crs.from_geographic);
  EXPECT_TRUE(crs.projected);

  // The .prj of the result: WGS 84 transverse Mercator on zone 55's meridian with the southern false northing.
  for (const char* part : {"PROJCS[\"WGS_1984_UTM_Zone_55S\"", "SPHEROID[\"WGS_1984\",6378137.0,298.257223563]",
                           "PROJECTION[\"Transverse_Mercator\"]", "PARAMETER[\"False_Easting\",500000.0]",
                           "PARAMETER[\"False_Northing\",10000000.0]", "PARAMETER[\"Central_Meridian\",147.0]",
                           "PARAMETER[\"Scale_Factor\",0.9996]", "PARAMETER[\"Latitude_Of_Origin\",0.0]",
                           "UNIT[\"Meter\",1.0]"})
    EXPECT_NE(crs.wkt.find(part), std::string::npos) << part << "\n" << crs.wkt;

  crs = choose_crs(katoomba, parse_crs("EPSG:7856"));
  EXPECT_NE(crs.wkt.find("PROJCS[\"GDA2020_MGA_Zone_56\""), std::string::npos) << crs.wkt;
  EXPECT_NE(crs.wkt.find("SPHEROID[\"GRS_1980\",6378137.0,298.257222101]"), std::string::npos) << crs.wkt;
  EXPECT_NE(crs.wkt.find("PARAMETER[\"Central_Meridian\",153.0]"), std::string::npos) << crs.wkt;
  crs = choose_crs(katoomba, parse_crs("33N"));
  EXPECT_NE(crs.wkt.find("PARAMETER[\"False_Northing\",0.0]"), std::string::npos) << crs.wkt;
}

TEST(ChooseCrs, ProjectedInputIsKeptWithItsPrj) {
  InputSet in;
  in.points = {{273741.297, 5796489.777, 10}, {274741.5, 5797489.25, 12}};
  in.lines.push_back({{{273800, 5796500, 11}, {273900, 5796600, 11}}, false, 0, 1});
  in.source_crs_wkt = "PROJCS[\"GDA2020_MGA_Zone_55\",GEOGCS[\"GCS_GDA2020\"]]";
  const InputSet before = in;
  const Crs crs = choose_crs(in, parse_crs("auto"));
  EXPECT_FALSE(crs.from_geographic);
  EXPECT_FALSE(crs.projected);
  EXPECT_EQ(crs.wkt, in.source_crs_wkt);
  EXPECT_EQ(crs.name, "GDA2020_MGA_Zone_55");
  project(in, crs);
  EXPECT_EQ(in.points, before.points);
  EXPECT_EQ(in.lines[0].points, before.lines[0].points);
}

TEST(ChooseCrs, ExplicitProjectionOfProjectedInputIsRejected) {
  InputSet in;
  in.points = {{273741.297, 5796489.777, 10}};
  for (const char* request : {"55S", "EPSG:7855", "32755"}) {
    try {
      choose_crs(in, parse_crs(request));
      FAIL() << request;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("not lon/lat"), std::string::npos) << e.what();
    }
  }
}

TEST(ChooseCrs, NoneKeepsLonLatAsRead) {
  InputSet in = lon_lat_points({{150.31, -33.71}});
  in.source_crs_wkt = "GEOGCS[\"GCS_GDA2020\"]";
  const Crs crs = choose_crs(in, parse_crs("none"));
  EXPECT_EQ(crs.name, "none");
  EXPECT_FALSE(crs.from_geographic);
  EXPECT_EQ(crs.wkt, in.source_crs_wkt);
  project(in, crs);
  EXPECT_EQ(in.points[0], (Point3{150.31, -33.71, 100}));
}

TEST(Project, MovesPointsAndEveryPolylineVertex) {
  InputSet in = lon_lat_points({{150.31, -33.71}});
  in.lines.push_back({{{150.30, -33.70, 900}, {150.32, -33.72, 900}}, false, 0, 1});
  in.lines.push_back({{{150.305, -33.705, 950}, {150.306, -33.705, 950}, {150.306, -33.706, 950}}, true, 0, 2});
  const Crs crs = choose_crs(in, parse_crs("auto"));
  project(in, crs);
  // Each vertex equals the same point projected on its own, and z is untouched.
  for (const Polyline& l : in.lines)
    for (const Point3& p : l.points) {
      EXPECT_GT(p.x, 100000);
      EXPECT_LT(p.x, 900000);
      EXPECT_GT(p.y, 6000000);
      EXPECT_LT(p.y, 10000000);
    }
  const Point3 alone = project_one("56S", 150.32, -33.72);
  EXPECT_EQ(in.lines[0].points[1].x, alone.x);
  EXPECT_EQ(in.lines[0].points[1].y, alone.y);
  EXPECT_EQ(in.lines[0].points[1].z, 900);
  EXPECT_EQ(in.lines[1].points[2].z, 950);
}

}  // namespace
}  // namespace cdtgpu

namespace cdtgpu {

// The datum of a geographic .prj decides the projection: GDA2020 and GDA94 data go to their MGA zone (what
// Australian users expect), WGS 84 and data without a .prj to UTM; an unknown datum is refused.
TEST(ChooseCrs, GdaDataGoesToItsMgaZone) {
  InputSet k = lon_lat_points({{150.30, -33.70}, {150.32, -33.72}});
  k.source_crs_wkt =
      "GEOGCS[\"GCS_GDA2020\",DATUM[\"D_GDA2020\",SPHEROID[\"GRS_1980\",6378137.0,298.257222101]],"
      "PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]";
  Crs crs = choose_crs(k, parse_crs("auto"));
  EXPECT_EQ(crs.epsg, 7856);
  EXPECT_EQ(crs.name, "GDA2020 / MGA zone 56");
  k.source_crs_wkt = "GEOGCS[\"GCS_GDA_1994\",DATUM[\"D_GDA_1994\",SPHEROID[\"GRS_1980\",6378137.0,298.257222101]]]";
  EXPECT_EQ(choose_crs(k, parse_crs("auto")).epsg, 28356);
  k.source_crs_wkt = "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137.0,298.257223563]]]";
  EXPECT_EQ(choose_crs(k, parse_crs("auto")).epsg, 32756);
  // An explicit zone or code still wins.
  EXPECT_EQ(choose_crs(k, parse_crs("EPSG:7856")).epsg, 7856);
  k.source_crs_wkt = "GEOGCS[\"GCS_North_American_1983\",DATUM[\"D_North_American_1983\"]]";
  EXPECT_THROW(choose_crs(k, parse_crs("auto")), InputError);
  EXPECT_EQ(choose_crs(k, parse_crs("none")).name, "none");
  // GDA data north of the equator has no MGA zone: UTM on WGS 84.
  InputSet north = lon_lat_points({{150.30, 10.0}, {150.32, 10.1}});
  north.source_crs_wkt = "GEOGCS[\"GCS_GDA2020\",DATUM[\"D_GDA2020\"]]";
  EXPECT_EQ(choose_crs(north, parse_crs("auto")).epsg, 32656);
}

TEST(ChooseCrs, ProjectedMgaAndUtmInputIsRecognised) {
  InputSet p = lon_lat_points({});
  p.points = {{250000, 6260000, 0}, {250100, 6260100, 0}};
  p.source_crs_wkt = "PROJCS[\"GDA2020_MGA_Zone_56\",GEOGCS[\"GCS_GDA2020\"]]";
  Crs crs = choose_crs(p, parse_crs("auto"));
  EXPECT_FALSE(crs.from_geographic);
  EXPECT_EQ(crs.epsg, 7856);
  EXPECT_EQ(crs.name, "GDA2020_MGA_Zone_56");
  p.source_crs_wkt = "PROJCS[\"GDA_1994_MGA_Zone_55\",GEOGCS[\"GCS_GDA_1994\"]]";
  EXPECT_EQ(choose_crs(p, parse_crs("auto")).epsg, 28355);
  p.source_crs_wkt = "PROJCS[\"WGS_1984_UTM_Zone_56S\",GEOGCS[\"GCS_WGS_1984\"]]";
  EXPECT_EQ(choose_crs(p, parse_crs("auto")).epsg, 32756);
  p.source_crs_wkt = "PROJCS[\"WGS_1984_UTM_Zone_33N\",GEOGCS[\"GCS_WGS_1984\"]]";
  EXPECT_EQ(choose_crs(p, parse_crs("auto")).epsg, 32633);
  p.source_crs_wkt = "PROJCS[\"NAD_1983_StatePlane_Texas\",GEOGCS[\"GCS_North_American_1983\"]]";
  EXPECT_EQ(choose_crs(p, parse_crs("auto")).epsg, 0);
}

}  // namespace cdtgpu
