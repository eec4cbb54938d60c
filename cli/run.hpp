// The commands behind the CLI: triangulate (the stages of cli/stages.hpp in a row) and verify.
#pragma once
#include <string>

#include "cli/job.hpp"

namespace cdtgpu {

// Returns the process exit code; throws InputError / UsageError for bad input.
int run_triangulate(const TriangulateOptions& options);
int run_verify(const std::string& mesh_path, const InputOptions& options, double max_edge = 0);

}  // namespace cdtgpu
