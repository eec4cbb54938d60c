// `-o dem.xyz` with dem.xyz among the inputs used to replace the input with the mesh and exit 0; `-o
// contours.ply` beside contours.shp replaced the input's contours.prj with the output's CRS. Both are
// caught here by file identity (st_dev, st_ino), so another spelling of the path (./x, a link, a hard link)
// is caught too.
#include "io/output_guard.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;

std::optional<std::pair<dev_t, ino_t>> identity(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return std::make_pair(st.st_dev, st.st_ino);
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// An input and the files read with it, each with a note for the message.
std::vector<std::pair<std::string, std::string>> files_read(const std::string& input) {
  std::vector<std::pair<std::string, std::string>> files = {{input, "the input " + input}};
  if (lower(fs::path(input).extension().string()) != ".shp") return files;
  for (const char* ext : {".shx", ".dbf", ".prj", ".SHX", ".DBF", ".PRJ"}) {
    const std::string p = fs::path(input).replace_extension(ext).string();
    files.emplace_back(p, "the input " + input + "'s " + lower(ext) + " file " + p);
  }
  return files;
}

std::string normal(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return ec ? fs::path(path).lexically_normal().string() : p.string();
}

}  // namespace

std::vector<std::string> triangulate_outputs(const std::string& mesh, const std::string& stats) {
  std::vector<std::string> out;
  if (!mesh.empty()) {  // empty with --tiles-out alone
    out.push_back(mesh);
    // The writer puts the CRS beside a regular output file (io/writers.cpp write_mesh_file).
    if (!is_special_output(mesh)) out.push_back(fs::path(mesh).replace_extension(".prj").string());
  }
  if (!stats.empty()) out.push_back(stats);
  return out;
}

void check_outputs_spare_inputs(const std::vector<std::string>& inputs,
                                const std::vector<std::string>& outputs) {
  if (std::count(outputs.begin(), outputs.end(), "-") > 1)
    throw UsageError("only one output can go to stdout (-): the mesh and the stats would be mixed");
  for (size_t i = 0; i < outputs.size(); ++i) {
    const std::string& out = outputs[i];
    if (out == "-") continue;
    // A missing folder used to fail only at the end, after the whole triangulation (exit 3).
    const fs::path folder = fs::path(out).parent_path();
    std::error_code ec;
    if (!folder.empty() && !fs::is_directory(folder, ec))
      throw UsageError("cannot write " + out + ": there is no folder " + folder.string());
    const auto id = identity(out);
    if (id && !is_special_output(out)) {
      for (const std::string& input : inputs) {
        if (input == "-") continue;
        for (const auto& [file, what] : files_read(input))
          if (identity(file) == id)
            throw UsageError("the output " + out + " is " + what +
                             " (the same file): refusing to overwrite an input; choose another output path");
      }
    }
    for (size_t j = 0; j < i; ++j) {
      const bool same = (id && identity(outputs[j]) == id) || normal(outputs[j]) == normal(out);
      if (same && !is_special_output(out))
        throw UsageError("the outputs " + outputs[j] + " and " + out +
                         " are the same file: one would overwrite the other");
    }
  }
}

}  // namespace cdtgpu
