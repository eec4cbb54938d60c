// Input readers. Each appends to an InputSet through core/repair.hpp, so repairs are counted one way.
#pragma once
#include <istream>
#include <string>
#include <string_view>

#include "core/model.hpp"

namespace cdtgpu {

struct ReadOptions {
  std::string z_field;  // DBF attribute giving z (shapefiles); empty: z from the geometry, else 0
};

// Dispatches on the extension (.shp, .wkt, .xyz/.csv/.txt, .asc); "-" reads WKT from stdin.
// Throws InputError naming the file and record/line for malformed or unknown input.
void read_input(const std::string& path, const ReadOptions& options, InputSet& in);

void read_shapefile(const std::string& path, const ReadOptions& options, InputSet& in);
void read_wkt(std::istream& text, const std::string& name, InputSet& in);
void read_xyz(std::istream& text, const std::string& name, InputSet& in);
// The same on a whole text (a mapped file): parsed on all cores, with the same results and messages.
void read_wkt_text(std::string_view text, const std::string& name, InputSet& in);
void read_xyz_text(std::string_view text, const std::string& name, InputSet& in);
void read_ascii_grid(std::istream& text, const std::string& name, InputSet& in);

// The text format of ../shared/data/cdt-peer-inputs: "V E", V lines "x y", E lines "i j" (0-based).
void read_peer_input(std::istream& text, const std::string& name, InputSet& in);

}  // namespace cdtgpu
