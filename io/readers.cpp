// read_input: picks a reader from the file's extension and opens the file, so that every reader sees
// either a stream (text formats) or a path (shapefiles, which come as several files).
#include "io/readers.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <spdlog/spdlog.h>

#include "core/error.hpp"
#include "io/geotiff.hpp"
#include "io/read_geojson.hpp"
#include "io/read_las.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// Opens a text input; the checks come first so that a directory or a missing file gets a plain message.
std::ifstream open_text(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, "is a directory, not a file");
  // Binary mode: the readers treat '\r' as white space, so CRLF files read the same everywhere.
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  return file;
}

// Mapped whole and parsed on all cores.
template <typename Reader>
void read_mapped(const std::string& path, Reader reader, InputSet& in) {
  open_text(path);  // the plain messages for a missing file or a directory
  const TextSource src = TextSource::open(path);
  reader(src.text(), path, in);
}

}  // namespace

void read_input(const std::string& path, const ReadOptions& options, InputSet& in) {
  if (path == "-") {
    read_wkt(std::cin, "<stdin>", in);
    return;
  }
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".shp")
    read_shapefile(path, options, in);
  else if (ext == ".wkt")
    read_mapped(path, read_wkt_text, in);
  else if (ext == ".xyz" || ext == ".csv" || ext == ".txt")
    read_mapped(path, [&](std::string_view text, const std::string& name, InputSet& set) {
      read_xyz_text(text, name, set, options.share);
    }, in);
  else if (ext == ".asc")
    read_mapped(path, read_ascii_grid_text, in);
  else if (ext == ".tif" || ext == ".tiff")
    read_geotiff(path, in);
  else if (ext == ".geojson" || ext == ".json")
    read_mapped(path, [&](std::string_view text, const std::string& name, InputSet& set) {
      read_geojson_text(text, name, options.z_field, set);
    }, in);
  else if (ext == ".las")
    read_las(path, LasFilter{}, in, options.share);
  else if (ext == ".laz")
    throw InputError(path, 0,
                     "LAZ (compressed LAS) is not read: decompress it first, e.g. `laszip -i in.laz -o out.las` "
                     "(LAStools) or `pdal translate in.laz out.las`, and give the .las");
  else
    throw InputError(path, 0,
                     "unknown input format '" + (ext.empty() ? std::string("(no extension)") : ext) +
                         "' (expected .shp, .wkt, .xyz, .csv, .txt, .asc, .tif, .geojson, .json or .las, or - for "
                         "WKT on stdin)");
}

GlobalZField::GlobalZField(const ReadOptions& options) : options_(options) {}

void GlobalZField::read(const std::string& path, InputSet& in) {
  if (options_.z_field.empty() || path == "-" || lower(std::filesystem::path(path).extension().string()) != ".shp") {
    ReadOptions options = options_;
    options.z_field.clear();  // --z-field is a shapefile field; a GeoJSON property is named per input (z=NAME)
    read_input(path, options, in);
    return;
  }
  any_shapefile_ = true;
  ZFieldLookup lookup;
  read_shapefile(path, options_, in, &lookup);
  if (lookup.found)
    found_ = true;
  else
    without_.emplace_back(path, lookup.why_not);
}

void GlobalZField::finish() const {
  if (options_.z_field.empty()) return;
  // --z-field NOPE used to be ignored without a word for Z shapefiles (their geometry's z was kept); the rule is
  // now that some input must have the field, so a misspelt name fails while contours with ELEV read along with
  // footprints without it (the README's sample) still work.
  if (!any_shapefile_)
    throw UsageError("--z-field " + options_.z_field + " reads z from a shapefile's attributes, and no input is a "
                     "shapefile");
  if (!found_) {
    std::string why;
    for (const auto& [path, reason] : without_) why += (why.empty() ? "" : "; ") + path + ": " + reason;
    throw InputError(without_.front().first, 0,
                     "no input shapefile has the z field " + options_.z_field + " (" + why + ")");
  }
  for (const auto& [path, reason] : without_) spdlog::info("{}: {}: z from its geometry", path, reason);
}

void read_inputs(const std::vector<std::string>& paths, const ReadOptions& options, InputSet& in) {
  GlobalZField reader(options);
  for (const std::string& path : paths) reader.read(path, in);
  reader.finish();
}

}  // namespace cdtgpu
