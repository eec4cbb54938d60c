// Output that appears whole or not at all: written to a temporary file beside the target, then renamed.
#pragma once
#include <functional>
#include <ostream>
#include <string>

namespace cdtgpu {

// Calls write(stream) on a temporary file in the target's folder and renames it to path on success; on any
// exception the temporary file is removed and the exception rethrown. "-" writes to stdout directly.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace cdtgpu
