// Refuses, before anything is read, a run whose output would overwrite one of its inputs.
#pragma once
#include <string>
#include <vector>

namespace cdtgpu {

// Throws UsageError (exit code 2) when a path in outputs is the same file (same device and inode, links
// followed) as an input or an input's companion (.shx, .dbf, .prj beside a .shp), or names the same file as
// another output. Paths that do not exist yet cannot clash with an input; they are compared by their
// absolute, normalised form with each other. "-" (stdout) may appear once. An output whose folder does not
// exist is refused too (it used to fail only after the whole triangulation).
void check_outputs_spare_inputs(const std::vector<std::string>& inputs,
                                const std::vector<std::string>& outputs);

// The files a run of triangulate writes: the mesh (none when `mesh` is empty), its .prj sidecar (for a regular
// output file), the stats.
std::vector<std::string> triangulate_outputs(const std::string& mesh, const std::string& stats);

}  // namespace cdtgpu
