// Per-input options on the command line: PATH[:key=value,...], e.g. contours.shp:z=ELEV, lakes.shp:role=hole,
// footprints.shp:role=breakline,z=drape. Keys: role (breakline, vertices, boundary, hole) and z (a shapefile
// field or GeoJSON property name, a number, drape, min, mean or max); for LAS inputs class (class=2 or
// class=2,8,9), returns (all, first, last) and withheld (skip, keep). Global options (--z-field) are the
// defaults.
//
//   std::vector<InputSpec> specs;
//   for (const std::string& arg : args) specs.push_back(parse_input_spec(arg));
//   InputSet in;
//   std::vector<InputPart> parts = read_inputs(specs, read_options, in);   // what each input added
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/input_parts.hpp"
#include "core/model.hpp"
#include "io/read_las.hpp"
#include "io/readers.hpp"

namespace cdtgpu {

struct InputSpec {
  std::string path;
  Role role = Role::breakline;
  ZRule z;                             // keep unless z= gave a number, drape, min, mean or max
  std::optional<std::string> z_field;  // z=NAME: the shapefile field (overrides --z-field) or GeoJSON property
  std::optional<LasFilter> las;        // class=, returns=, withheld= given (LAS inputs only)
};

// A path that exists is taken whole. Otherwise the text after the last ':' is options when every
// comma-separated item is key=value; an unknown key or value is a UsageError naming it. Anything else (no
// ':', or an item without '=') is a plain path.
InputSpec parse_input_spec(const std::string& arg);

// Reads each input with its own options (z field, role); lines of role=vertices inputs become points.
// Returns, per input, the points and lines it added to `in`. Vertices without z (2D geometry and no z field)
// get a NaN z (InputSet::nan_for_missing_z): call core/drape's apply_z_rules before prepare.
std::vector<InputPart> read_inputs(const std::vector<InputSpec>& specs, const ReadOptions& defaults,
                                   InputSet& in);

}  // namespace cdtgpu
