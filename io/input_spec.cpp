// parse_input_spec and read_inputs: the per-input suffix of the command line and reading with it.
#include "io/input_spec.hpp"

#include <spdlog/spdlog.h>

#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string_view>

#include "core/error.hpp"
#include "io/read_share.hpp"

namespace cdtgpu {

namespace {

std::optional<double> number(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<std::string_view> split(std::string_view s, char c) {
  std::vector<std::string_view> items;
  for (size_t at = 0;;) {
    const size_t next = s.find(c, at);
    items.push_back(s.substr(at, next == std::string_view::npos ? std::string_view::npos : next - at));
    if (next == std::string_view::npos) return items;
    at = next + 1;
  }
}

// An ASPRS class in a class= list: 0 to 255.
bool is_class_number(std::string_view s) {
  int v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && end == s.data() + s.size() && v >= 0 && v <= 255;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

InputSpec parse_input_spec(const std::string& arg) {
  InputSpec spec;
  spec.path = arg;
  std::error_code ec;
  const size_t colon = arg.rfind(':');
  if (colon == std::string::npos || colon == 0 || std::filesystem::exists(arg, ec)) return spec;
  const std::string_view suffix = std::string_view(arg).substr(colon + 1);
  const std::vector<std::string_view> items = split(suffix, ',');
  bool in_class = false;  // class=2,8,9: the numbers after the first are items of their own
  for (std::string_view item : items) {
    if (item.find('=') != std::string_view::npos)
      in_class = item.substr(0, item.find('=')) == "class";
    else if (!in_class || !is_class_number(item))
      return spec;  // not options: a path with a ':'
  }
  spec.path = arg.substr(0, colon);
  bool seen_role = false, seen_z = false, seen_class = false, seen_returns = false, seen_withheld = false;
  for (size_t i = 0; i < items.size(); ++i) {
    const std::string_view item = items[i];
    const size_t eq = item.find('=');
    const std::string where = " in '" + arg + "'";
    const std::string key(item.substr(0, eq)), value(item.substr(eq + 1));
    if (key == "class") {
      if (seen_class) throw UsageError("class given twice" + where);
      seen_class = true;
      LasFilter& las = spec.las ? *spec.las : spec.las.emplace();
      las.classes.reset();
      for (std::string_view c = value;; c = items[++i]) {
        if (!is_class_number(c))
          throw UsageError("class '" + std::string(c) + "'" + where + " is not an ASPRS class number 0 to 255");
        las.classes.set(size_t(std::stoi(std::string(c))));
        if (i + 1 == items.size() || !is_class_number(items[i + 1])) break;
      }
    } else if (key == "returns") {
      if (seen_returns) throw UsageError("returns given twice" + where);
      seen_returns = true;
      LasFilter& las = spec.las ? *spec.las : spec.las.emplace();
      if (value == "all")
        las.returns = LasFilter::Returns::all;
      else if (value == "first")
        las.returns = LasFilter::Returns::first;
      else if (value == "last")
        las.returns = LasFilter::Returns::last;
      else
        throw UsageError("unknown returns '" + value + "'" + where + " (use all, first or last)");
    } else if (key == "withheld") {
      if (seen_withheld) throw UsageError("withheld given twice" + where);
      seen_withheld = true;
      LasFilter& las = spec.las ? *spec.las : spec.las.emplace();
      if (value == "skip")
        las.keep_withheld = false;
      else if (value == "keep")
        las.keep_withheld = true;
      else
        throw UsageError("unknown withheld '" + value + "'" + where + " (use skip or keep)");
    } else if (key == "role") {
      if (seen_role) throw UsageError("role given twice" + where);
      seen_role = true;
      if (value == "breakline")
        spec.role = Role::breakline;
      else if (value == "vertices")
        spec.role = Role::vertices;
      else if (value == "boundary")
        spec.role = Role::boundary;
      else if (value == "hole")
        spec.role = Role::hole;
      else
        throw UsageError("unknown role '" + value + "'" + where +
                         " (use breakline, vertices, boundary or hole)");
    } else if (key == "z") {
      if (seen_z) throw UsageError("z given twice" + where);
      seen_z = true;
      if (value.empty())
        throw UsageError("z needs a value" + where + " (a field name, a number, drape, min, mean or max)");
      if (value == "drape")
        spec.z.kind = ZRule::Kind::drape;
      else if (value == "min")
        spec.z.kind = ZRule::Kind::min;
      else if (value == "mean")
        spec.z.kind = ZRule::Kind::mean;
      else if (value == "max")
        spec.z.kind = ZRule::Kind::max;
      else if (std::optional<double> v = number(value))
        spec.z = {ZRule::Kind::constant, *v};
      else
        spec.z_field = value;
    } else {
      throw UsageError("unknown input option '" + key + "'" + where + " (known: role, z; class, returns, withheld for LAS)");
    }
  }
  return spec;
}

namespace {

// One input read in shares (io/read_share.hpp): this process's share into a piece of its own, then every
// share's piece joined into `in`. Formats without a share reader are read whole by one process: input k by
// process k % count, stdin by the first (the one mpirun gives it to).
template <typename Read>
void read_share(const InputSpec& spec, const std::string& ext, ReadOptions options, Read&& read, InputSet& in) {
  const ReadShare& share = *options.share;
  const bool by_records = ext == ".xyz" || ext == ".csv" || ext == ".txt" || ext == ".shp" || ext == ".las";
  const size_t input = in.sources.size();  // each input adds one source
  const uint32_t owner = spec.path == "-" ? 0 : uint32_t(input % share.count);
  InputSet piece;
  piece.nan_for_missing_z = in.nan_for_missing_z;
  piece.sources = in.sources;
  if (by_records) {
    read(options, piece);
  } else if (owner == share.index) {
    options.share = nullptr;
    read(options, piece);
  } else {
    piece.sources.push_back(spec.path == "-" ? "<stdin>" : spec.path);
  }
  in.sources = piece.sources;
  const size_t before = in.points.size() + in.lines.size();
  const PointClassCounts classes = join_shares(piece, share, in);
  if (share.index == 0 && in.points.size() + in.lines.size() == before)
    throw InputError(spec.path, 0, ext == ".las" ? las_nothing_kept(classes) : "no geometry");
}

}  // namespace

std::vector<InputPart> read_inputs(const std::vector<InputSpec>& specs, const ReadOptions& defaults,
                                   InputSet& in) {
  std::vector<InputPart> parts;
  in.nan_for_missing_z = true;
  GlobalZField global(defaults);  // inputs without their own z=FIELD: --z-field must be in some shapefile
  for (const InputSpec& spec : specs) {
    ReadOptions options = defaults;
    const std::string ext = lower_extension(spec.path);
    const bool shapefile = ext == ".shp", geojson = ext == ".geojson" || ext == ".json";
    if (spec.z_field) {
      if (!shapefile && !geojson)
        throw UsageError("z=" + *spec.z_field + " names an attribute field, which only shapefiles and GeoJSON have (" +
                         spec.path + "); z takes a number, drape, min, mean or max");
      options.z_field = *spec.z_field;
    } else if (!shapefile) {
      options.z_field.clear();  // --z-field is a shapefile field
    }
    if (spec.las && ext != ".las")
      throw UsageError(spec.path + ": class=, returns= and withheld= select points of LAS inputs (.las)");
    InputPart part;
    part.points_begin = in.points.size();
    part.lines_begin = in.lines.size();
    const auto t0 = std::chrono::steady_clock::now();
    auto read = [&](const ReadOptions& options, InputSet& to) {
      if (ext == ".las")
        read_las(spec.path, spec.las.value_or(LasFilter{}), to, options.share);
      else if (spec.z_field || !shapefile)
        read_input(spec.path, options, to);  // its own field (required), or not a shapefile
      else
        global.read(spec.path, to);
    };
    if (defaults.share)
      read_share(spec, ext, options, read, in);
    else
      read(options, in);
    if (spec.role == Role::vertices) {
      for (size_t i = part.lines_begin; i < in.lines.size(); ++i)
        in.points.insert(in.points.end(), in.lines[i].points.begin(), in.lines[i].points.end());
      in.lines.resize(part.lines_begin);
    }
    part.points_end = in.points.size();
    part.lines_end = in.lines.size();
    spdlog::debug("read: {}: {} points, {} lines in {:.1f} ms", spec.path, part.points_end - part.points_begin,
                  part.lines_end - part.lines_begin,
                  std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const bool joined_here = !defaults.share || defaults.share->index == 0;  // the others sent theirs away
    if (joined_here && is_region_role(spec.role) && part.lines_end == part.lines_begin)
      throw UsageError(spec.path + ": role=" + (spec.role == Role::boundary ? "boundary" : "hole") +
                       " needs polygons (rings), and this input has only points");
    part.role = spec.role;
    part.z = spec.z;
    // Every vertex read with a z: drape does not look for missing ones (250M contour vertices: ~40 ms at 1B).
    part.z_complete = ext == ".las" || ext == ".asc" || ext == ".tif" || ext == ".tiff" ||
                      (shapefile && options.z_field.empty() && shapefile_has_z(spec.path));
    parts.push_back(part);
  }
  global.finish();
  return parts;
}

}  // namespace cdtgpu
