// Output that appears whole or not at all, without destroying what the output path names.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
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

// A regular file (or none yet) replaced in steps, for output begun before all of it is known
// (io/mesh_file_ahead): its temporary file is made at once and written at offsets, then synced and renamed over
// the path (commit), or removed (dropped uncommitted: the destructor, a failed write or commit). A signal
// removes it as it does write_file_atomically's.
class ReplacingFile {
 public:
  // Null for what write_file_atomically writes in place or to stdout (is_special_output).
  static std::unique_ptr<ReplacingFile> open(const std::string& path);
  // path: as the user named it (for messages); target: the file it names (links resolved); exists, mode: that
  // file's.
  ReplacingFile(const std::string& path, const std::string& target, bool exists, unsigned mode);
  ReplacingFile(const ReplacingFile&) = delete;
  ReplacingFile& operator=(const ReplacingFile&) = delete;
  ~ReplacingFile();

  // write(stream) at byte `offset`, from one thread at a time; returns the offset after what it wrote. Throws as
  // write_file_atomically does (the temporary file then removed).
  uint64_t write_at(uint64_t offset, const std::function<void(std::ostream&)>& write);
  void commit();

 private:
  void drop();
  std::string path_, target_, tmp_;
  bool exists_ = false;
  bool temp_ = false;  // the temporary file is there and ours to remove
  int fd_ = -1, slot_ = -1;
  double written_ms_ = 0;
};

// Removes what runs killed while writing `target` left beside it: the files (or, with `folders`, the folders)
// named `<target>` + `tag` + digits (".tmp-" and a pid), other than `own`, that no process holds locked (each
// run locks its own until it renames it into place; where the file system takes no locks, nothing is
// removed). Each removal is said (info), named by `what`. A folder's names are read once a process: what a
// run killed later leaves there, a later process removes.
void remove_killed_runs_temps(const std::string& target, const std::string& own, bool folders,
                              const std::string& what, const std::string& tag = ".tmp-");

// True for "-" and for paths written in place (see above): a sidecar beside such a path (a .prj) makes no
// sense.
bool is_special_output(const std::string& path);

}  // namespace cdtgpu
