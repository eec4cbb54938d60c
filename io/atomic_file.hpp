// Output that appears whole or not at all, without destroying what the output path names.
#pragma once
#include <functional>
#include <ostream>
#include <string>

namespace cdtgpu {

// Writes through write(stream) and checks every write, flush and close; a failure throws
// std::runtime_error "PATH: write failed: <OS error>" (exit code 3 in the CLI). What happens depends on what
// path names:
// - "-": stdout.
// - a regular file, or nothing yet: a temporary file "<path>.tmp-<pid>" beside it, synced and renamed over
//   path at the end (an existing file keeps its permissions); on any exception, or on SIGINT / SIGTERM /
//   SIGHUP, the temporary file is removed and the old file is left as it was.
// - a symbolic link: resolved; its target is replaced the same way (the link stays a link).
// - anything else that exists (a device such as /dev/null, a FIFO, a socket, /dev/stdout, /dev/fd/N): opened
//   and written in place; no temporary file, so an interrupted write leaves what was written so far.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// True for "-" and for paths written in place (see above): a sidecar beside such a path (a .prj) makes no
// sense.
bool is_special_output(const std::string& path);

}  // namespace cdtgpu
