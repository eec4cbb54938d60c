// The options of `cdtgpu triangulate` and `verify`, defined once: the command line (cli/main.cpp) and each line
// of a batch's job file (cli/batch.cpp) are parsed by the same CLI11 definitions.
//
//   TriangulateArgs args;
//   add_triangulate_options(app.add_subcommand("triangulate", "..."), args);
//   app.parse(argc, argv);
//   TriangulateOptions o = triangulate_options(args);    // --crs / --utm-zone / --epsg checked
#pragma once
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/job.hpp"

namespace cdtgpu {

// What the CRS options say, as typed; crs_from turns them into one request.
struct CrsArgs {
  std::string crs = "auto", utm_zone, epsg;
};

struct TriangulateArgs {
  TriangulateOptions tri;
  CrsArgs crs;
};

void add_input_options(CLI::App* cmd, InputOptions& in, CrsArgs& crs);
void add_triangulate_options(CLI::App* cmd, TriangulateArgs& args);
// verify's own: --max-edge, the value the mesh was made with.
void add_verify_options(CLI::App* cmd, double& max_edge);

// Throws UsageError when more than one of --crs, --utm-zone and --epsg is given.
CrsRequest crs_from(const CrsArgs& args);
TriangulateOptions triangulate_options(const TriangulateArgs& args);

// What `cdtgpu batch` gives every job whose line does not say otherwise.
struct JobDefaults {
  std::string backend;  // empty: the line's (default auto)
  std::string device;
};

// One job line's words, as `cdtgpu triangulate` takes them (the word `triangulate` first is optional; -v and
// -q are accepted and left to the batch's own logging). Throws UsageError with CLI11's message.
TriangulateOptions parse_job_words(std::vector<std::string> words, const JobDefaults& defaults);

}  // namespace cdtgpu
