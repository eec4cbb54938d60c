// Input readers. Each appends to an InputSet through core/repair.hpp, so repairs are counted one way.
#pragma once
#include <istream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

struct ReadShare;  // io/read_share.hpp

struct ReadOptions {
  std::string z_field;  // DBF attribute giving z (shapefiles), or GeoJSON feature property; empty: from geometry
  // Read only this share of each input, among several processes (io/read_share.hpp); null: everything.
  const ReadShare* share = nullptr;
};

// Dispatches on the extension (.shp, .wkt, .xyz/.csv/.txt, .asc, .tif/.tiff: io/geotiff.hpp, .geojson/.json,
// .las with every point but the withheld: io/read_las.hpp); "-" reads WKT from stdin.
// Throws InputError naming the file and record/line for malformed or unknown input.
void read_input(const std::string& path, const ReadOptions& options, InputSet& in);

// Reads every input in order. A z field (ReadOptions::z_field) must be in the .dbf of at least one shapefile
// input; a shapefile with z in its geometry but without the field keeps its geometry's z (logged), one without
// z must have it. Throws InputError naming each shapefile and the fields it has when none has the field, and
// UsageError when no input is a shapefile.
void read_inputs(const std::vector<std::string>& paths, const ReadOptions& options, InputSet& in);

// read_inputs one input at a time, for callers that mix inputs under the global z field with others.
class GlobalZField {
 public:
  explicit GlobalZField(const ReadOptions& options);
  void read(const std::string& path, InputSet& in);  // one input, under options.z_field
  void finish() const;                               // throws as read_inputs does
 private:
  ReadOptions options_;
  bool any_shapefile_ = false, found_ = false;
  std::vector<std::pair<std::string, std::string>> without_;  // shapefile, why
};

// Alone, a shapefile must have the z field when one is asked for (InputError listing the fields it has).
void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in);
// For read_inputs: a Z shapefile without the z field is read with its geometry's z and reported here.
struct ZFieldLookup {
  bool found = false;
  std::string why_not;  // no .dbf, or "no field F in X.dbf (fields: ...)"
};
void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in, ZFieldLookup* lookup);
// Whether a shapefile's header gives a Z shape type: read without a z field, every vertex then has a finite z
// from its geometry (the reader refuses any other).
bool shapefile_has_z(const std::string& path);
void read_wkt(std::istream& text, const std::string& name, InputSet& in);
void read_xyz(std::istream& text, const std::string& name, InputSet& in);
// The same on a whole text (a mapped file): parsed on all cores, with the same results and messages.
void read_wkt_text(std::string_view text, const std::string& name, InputSet& in);
// With a share: its lines only, no "no geometry" check (the caller's, once the shares are joined).
void read_xyz_text(std::string_view text, const std::string& name, InputSet& in, const ReadShare* share = nullptr);
void read_ascii_grid(std::istream& text, const std::string& name, InputSet& in);
// The same on text in memory, parsed on all cores.
void read_ascii_grid_text(std::string_view text, const std::string& name, InputSet& in);

// The text format of ../shared/data/cdt-peer-inputs: "V E", V lines "x y", E lines "i j" (0-based).
void read_peer_input(std::istream& text, const std::string& name, InputSet& in);

}  // namespace cdtgpu
