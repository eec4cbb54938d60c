// Whole-or-nothing output that never replaces what is not a regular file. A regular file is written to
// "<path>.tmp-<pid>" in its own folder (so the rename stays on one file system and is atomic), synced, and
// renamed over it. Renaming over a device, a FIFO or a symbolic link would replace the node itself (/dev/full
// would become a plain file, a link would stop pointing at its target), so those are handled apart: links are
// followed to the file they name, other non-regular files are written in place. Every write, sync and close
// is checked: std::ofstream's close cannot report a failed final flush, so the bytes go through write(2).
#include "io/atomic_file.hpp"

#include <spdlog/spdlog.h>

#include <chrono>

#include <fcntl.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <streambuf>
#include <thread>
#include <utility>
#include <vector>

namespace cdtgpu {

namespace {

namespace fs = std::filesystem;

// ---- the temporary files removed on SIGINT / SIGTERM / SIGHUP ----
// A few at a time: outputs are written one after another, but a mesh file begun ahead (ReplacingFile) stays
// open beside the others. The handler uses only async-signal-safe calls (unlink, raise); SA_RESETHAND restores
// the default action, so the re-raised signal ends the process with the status a shell expects (128 + signal).
constexpr int kTempSlots = 4;
char g_temp_path[kTempSlots][4096];
volatile std::sig_atomic_t g_temp_armed[kTempSlots] = {};
std::mutex g_temp_mutex;

extern "C" void remove_temp_and_reraise(int sig) {
  for (int i = 0; i < kTempSlots; ++i)
    if (g_temp_armed[i]) ::unlink(g_temp_path[i]);
  ::raise(sig);
}

void install_signal_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN)
        continue;  // nohup: keep ignoring
      struct sigaction sa {};
      sa.sa_handler = remove_temp_and_reraise;
      sigemptyset(&sa.sa_mask);
      sa.sa_flags = SA_RESETHAND;
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

// The slot that now names tmp, or -1 (none free, or too long to keep: a signal then leaves it behind).
int arm_temp(const std::string& tmp) {
  install_signal_handlers();
  std::lock_guard lock(g_temp_mutex);
  if (tmp.size() >= sizeof g_temp_path[0]) return -1;
  for (int i = 0; i < kTempSlots; ++i)
    if (!g_temp_armed[i]) {
      std::memcpy(g_temp_path[i], tmp.c_str(), tmp.size() + 1);
      g_temp_armed[i] = 1;
      return i;
    }
  return -1;
}

void disarm_temp(int slot) {
  if (slot >= 0) g_temp_armed[slot] = 0;
}

// ---- a checked stream over a file descriptor ----

struct WriteError {
  int err;
};

// Buffers in 64 KiB and writes with write(2); a failed write throws WriteError, which std::ostream turns into
// badbit (and, with exceptions on, rethrows).
class FdBuf : public std::streambuf {
 public:
  // writeback: start the disk writes of each large block as soon as it is written (regular files that are
  // synced before their rename: the sync then waits for the last blocks only, not the whole file).
  // offset: where fd's writes begin (for the writeback's ranges).
  explicit FdBuf(int fd, bool writeback = false, uint64_t offset = 0)
      : fd_(fd), writeback_(writeback), written_(offset), flushed_(offset), buffer_(1 << 16) {
    setp(buffer_.data(), buffer_.data() + buffer_.size());
  }
  int error() const { return error_; }
  uint64_t end() const { return written_; }  // the offset after what was written (drained)
  // Writes what is buffered; false (and error() set) on failure.
  bool drain() {
    const char* p = pbase();
    size_t n = size_t(pptr() - pbase());
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return write_all(p, n);
  }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) throw WriteError{error_};
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n <= epptr() - pptr()) {
      std::memcpy(pptr(), s, size_t(n));
      pbump(int(n));
      return n;
    }
    // Large blocks (the writers hand over ~1 MiB) go straight to the OS after what is buffered.
    if (!drain() || !write_all(s, size_t(n))) throw WriteError{error_};
    return n;
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool write_all(const char* p, size_t n) {
    while (n > 0) {
      const ssize_t w = ::write(fd_, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      if (w == 0) {  // not expected from write(2); do not spin
        error_ = EIO;
        return false;
      }
      p += w;
      n -= size_t(w);
      written_ += uint64_t(w);
    }
    if (writeback_ && written_ - flushed_ >= (uint64_t(8) << 20)) {
      ::sync_file_range(fd_, off_t(flushed_), off_t(written_ - flushed_), SYNC_FILE_RANGE_WRITE);
      flushed_ = written_;
    }
    return true;
  }
  int fd_;
  bool writeback_;
  uint64_t written_, flushed_;
  std::vector<char> buffer_;
  int error_ = 0;
};

[[noreturn]] void fail(const std::string& path, const std::string& what, int err) {
  throw std::runtime_error(path + ": " + what + ": " + std::strerror(err));
}

// Runs write over fd and drains the buffer; throws "path: write failed: ..." on an OS error. Does not close
// fd.
// Returns the offset after what it wrote.
uint64_t write_fd(int fd, const std::string& path, const std::function<void(std::ostream&)>& write,
                  bool writeback = false, uint64_t offset = 0) {
  FdBuf buf(fd, writeback, offset);
  std::ostream out(&buf);
  out.exceptions(std::ios::badbit | std::ios::failbit);
  try {
    write(out);
    out.flush();
  } catch (const WriteError& e) {
    fail(path, "write failed", e.err);
  } catch (const std::ios_base::failure&) {
    fail(path, "write failed", buf.error() ? buf.error() : EIO);
  }
  if (!buf.drain()) fail(path, "write failed", buf.error());
  return buf.end();
}

void close_checked(int fd, const std::string& path) {
  // Linux releases the descriptor even when close fails (EINTR included): never retry.
  if (::close(fd) != 0 && errno != EINTR) fail(path, "write failed (close)", errno);
}

// The descriptor that /dev/stdout, /dev/stderr, /dev/fd/N or /proc/self/fd/N stands for, else -1. Writing to
// it directly keeps the shell's offset and append mode (opening the path again would truncate a redirected
// file, or fail for a socket).
int fd_path(const std::string& path) {
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    const std::string p = prefix;
    if (path.rfind(p, 0) != 0 || path.size() == p.size() || path.size() > p.size() + 6) continue;
    int fd = 0;
    for (size_t i = p.size(); i < path.size(); ++i) {
      if (path[i] < '0' || path[i] > '9') return -1;
      fd = fd * 10 + (path[i] - '0');
    }
    return fd;
  }
  return -1;
}

// What a path names, with symbolic links followed by hand (a dangling link names the file it would create).
struct Target {
  enum Kind { Fd, InPlace, Replace } kind = Replace;
  std::string path;  // InPlace: the path to open; Replace: the file to replace (links resolved)
  int fd = -1;       // Fd
  bool exists = false;
  mode_t mode = 0;
};

Target classify(const std::string& path) {
  Target t;
  if ((t.fd = fd_path(path)) >= 0) {
    t.kind = Target::Fd;
    return t;
  }
  fs::path p = path;
  for (int hops = 0;; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0) break;  // does not exist (yet): created by the rename
    if (S_ISLNK(st.st_mode)) {
      if (hops == 40) fail(path, "cannot write", ELOOP);
      std::error_code ec;
      fs::path next = fs::read_symlink(p, ec);
      if (ec) fail(path, "cannot resolve the link", ec.value());
      p = next.is_absolute() ? next : p.parent_path() / next;
      if (fd_path(p.string()) >= 0) return classify(p.string());  // e.g. /dev/stdout -> /proc/self/fd/1
      // Any other magic link of /proc (such as /proc/PID/fd/N) names no file that a rename could replace.
      if (p.string().rfind("/proc/", 0) == 0) {
        t.kind = Target::InPlace;
        t.path = path;
        return t;
      }
      continue;
    }
    t.exists = true;
    t.mode = st.st_mode;
    if (!S_ISREG(st.st_mode)) {
      t.kind = Target::InPlace;
      t.path = path;
      return t;
    }
    break;
  }
  t.kind = Target::Replace;
  t.path = p.string();
  return t;
}

void write_in_place(const std::string& path, const std::function<void(std::ostream&)>& write) {
  // O_TRUNC is ignored by devices and FIFOs; a directory fails here with EISDIR.
  const int fd = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) fail(path, "cannot open for writing", errno);
  try {
    write_fd(fd, path, write);
  } catch (...) {
    ::close(fd);
    throw;
  }
  close_checked(fd, path);
}

// The last reference to a replaced file, handed on. Its pages and blocks are freed when that reference goes,
// 25-57 ms for a 125 MB PLY on the H100 machine's disk: on a thread of this process the work still delays its
// exit, which waits for the thread's close (a single run writes its mesh last). So a short-lived child
// (/bin/true) inherits the file and frees it as it exits; this process's own close is then instant. The
// children are reaped at the next call (the rest go with the process). Without /bin/true: a thread.
void free_replaced(int fd) {
  static std::mutex mutex;
  static std::vector<pid_t> children;
  std::lock_guard lock(mutex);
  std::erase_if(children, [](pid_t pid) { return ::waitpid(pid, nullptr, WNOHANG) != 0; });
  posix_spawn_file_actions_t actions;
  pid_t pid = -1;
  bool spawned = false;
  if (::posix_spawn_file_actions_init(&actions) == 0) {
    const int at = fd == 3 ? 4 : 3;  // dup2 onto another number clears close-on-exec
    char arg0[] = "true";
    char* argv[] = {arg0, nullptr};
    spawned = ::posix_spawn_file_actions_adddup2(&actions, fd, at) == 0 &&
              ::posix_spawn(&pid, "/bin/true", &actions, nullptr, argv, environ) == 0;
    ::posix_spawn_file_actions_destroy(&actions);
  }
  if (!spawned) {
    std::thread([fd] { ::close(fd); }).detach();
    return;
  }
  children.push_back(pid);
  ::close(fd);  // the child holds it (posix_spawn returns once it runs /bin/true)
}

}  // namespace

ReplacingFile::ReplacingFile(const std::string& path, const std::string& target, bool exists, unsigned mode)
    : path_(path), target_(target), tmp_(target + ".tmp-" + std::to_string(::getpid())), exists_(exists) {
  remove_killed_runs_temps(target_, tmp_, false, "the temporary file");
  slot_ = arm_temp(tmp_);
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int err = errno;
    disarm_temp(slot_);
    fail(path, "cannot create " + tmp_, err);
  }
  temp_ = true;
  // Ours until the rename: another run's remove_killed_runs_temps leaves a locked file alone. Where the file system
  // takes no locks, the other run's flock fails too and removes nothing.
  (void)::flock(fd_, LOCK_EX | LOCK_NB);
  // The new file keeps the old one's permissions (umask applies to a new one only).
  if (exists && ::fchmod(fd_, mode & 07777) != 0) {
    const int err = errno;
    drop();
    fail(path, "cannot set the permissions of " + tmp_, err);
  }
}

std::unique_ptr<ReplacingFile> ReplacingFile::open(const std::string& path) {
  if (path == "-") return nullptr;
  const Target t = classify(path);
  if (t.kind != Target::Replace) return nullptr;
  return std::unique_ptr<ReplacingFile>(new ReplacingFile(path, t.path, t.exists, t.mode));
}

ReplacingFile::~ReplacingFile() { drop(); }

void ReplacingFile::drop() {
  if (fd_ >= 0) ::close(std::exchange(fd_, -1));
  if (!std::exchange(temp_, false)) return;
  ::unlink(tmp_.c_str());
  disarm_temp(slot_);
}

uint64_t ReplacingFile::write_at(uint64_t offset, const std::function<void(std::ostream&)>& write) {
  try {
    if (::lseek(fd_, off_t(offset), SEEK_SET) < 0) fail(path_, "write failed (seek)", errno);
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t end = write_fd(fd_, path_, write, true, offset);
    written_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return end;
  } catch (...) {
    drop();
    throw;
  }
}

void ReplacingFile::commit() {
  const auto t0 = std::chrono::steady_clock::now();
  // Synced before the rename, so that a crash can leave the old file or the new one, never an empty one.
  if (::fsync(fd_) != 0 && errno != EINVAL) {
    const int err = errno;
    drop();
    fail(path_, "write failed (sync)", err);
  }
  spdlog::debug("{}: written in {:.1f} ms, synced in {:.1f} ms", path_, written_ms_,
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  const int fd = std::exchange(fd_, -1);
  const int lock = ::dup(fd);  // the lock stays with the file until it is renamed
  struct LockHeld {
    int fd;
    ~LockHeld() {
      if (fd >= 0) ::close(fd);
    }
  } held{lock};
  if (::close(fd) != 0 && errno != EINTR) {
    const int err = errno;
    drop();
    fail(path_, "write failed (close)", err);
  }
  // The replaced file's pages and blocks are freed when the last reference to it goes, inside the rename
  // unless something holds it open: held here, they are freed elsewhere (free_replaced).
  const int replaced = exists_ ? ::open(target_.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK) : -1;
  if (::rename(tmp_.c_str(), target_.c_str()) != 0) {
    const int err = errno;
    if (replaced >= 0) ::close(replaced);
    drop();
    fail(path_, "cannot rename " + tmp_ + " into place", err);
  }
  temp_ = false;  // renamed: the path's file now
  disarm_temp(slot_);
  if (replaced >= 0) free_replaced(replaced);
}

namespace {

// The names in a folder that may be killed runs' leftovers (NAME.tmp-DIGITS, NAME.old-DIGITS, ...), read once
// a folder a process: read for each file written, a batch of 400 tiny jobs writing into a folder of 10K files
// took 5.6-5.9 s against 0.9 in an empty one. What a run killed after that read leaves, a later process
// removes.
class Leftovers {
 public:
  // A copy of the folder's candidates, read now if this process has not read them yet.
  std::vector<std::string> in(const fs::path& folder) {
    std::lock_guard lock(mutex_);
    auto [it, read_now] = by_folder_.try_emplace(folder.string());
    if (read_now) {
      std::error_code ec;
      for (fs::directory_iterator d(folder, ec), end; !ec && d != end; d.increment(ec))
        if (std::string name = d->path().filename().string(); maybe_leftover(name))
          it->second.push_back(name);
    }
    return it->second;
  }
  // One gone (removed here, or by another process): not tried again.
  void gone(const fs::path& folder, const std::string& name) {
    std::lock_guard lock(mutex_);
    std::erase(by_folder_[folder.string()], name);
  }

 private:
  // Any name ending in a dash and digits: remove_killed_runs_temps checks the target and the tag.
  static bool maybe_leftover(const std::string& name) {
    const size_t dash = name.rfind('-');
    return dash != std::string::npos && dash + 1 < name.size() &&
           name.find_first_not_of("0123456789", dash + 1) == std::string::npos;
  }
  std::mutex mutex_;
  std::map<std::string, std::vector<std::string>> by_folder_;
};

Leftovers& leftovers() {
  static Leftovers l;
  return l;
}

}  // namespace

// A run's temporary file or folder is locked (flock) from its creation to its rename, on any host that shares the
// folder (NFS takes flock on a file as a POSIX lock). One that nobody locks is what a run killed by SIGKILL (or
// the OOM killer) left: at 10^9 points tens of GB.
void remove_killed_runs_temps(const std::string& target, const std::string& own, bool folders,
                              const std::string& what, const std::string& tag) {
  const fs::path t(target);
  const fs::path folder = t.parent_path().empty() ? fs::path(".") : t.parent_path();
  const std::string prefix = t.filename().string() + tag;
  for (const std::string& name : leftovers().in(folder)) {
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    if (name.find_first_not_of("0123456789", prefix.size()) != std::string::npos) continue;
    if (name == fs::path(own).filename().string()) continue;
    const std::string p = (folder / name).string();
    const int fd = ::open(p.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      if (errno == ENOENT) leftovers().gone(folder, name);
      continue;
    }
    struct stat held {}, named {};
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::fstat(fd, &held) == 0 && ::lstat(p.c_str(), &named) == 0 &&
        named.st_ino == held.st_ino && named.st_dev == held.st_dev) {
      std::error_code failed;
      if (!folders && S_ISREG(held.st_mode) && ::unlink(p.c_str()) == 0) {
        leftovers().gone(folder, name);
        spdlog::info("removed {} ({} bytes), {} of an earlier run that was killed while writing {}", p,
                     uint64_t(held.st_size), what, target);
      } else if (folders && S_ISDIR(held.st_mode)) {
        if (const auto n = fs::remove_all(p, failed); !failed) {
          leftovers().gone(folder, name);
          spdlog::info("removed {} ({} files and folders), {} of an earlier run that was killed while writing {}",
                       p, n, what, target);
        }
      }
    }
    ::close(fd);
  }
}

bool is_special_output(const std::string& path) {
  if (path == "-") return true;
  return classify(path).kind != Target::Replace;
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (path == "-") {
    std::cout.flush();
    write_fd(1, "<stdout>", write);
    return;
  }
  const Target t = classify(path);
  switch (t.kind) {
    case Target::Fd:
      write_fd(t.fd, path, write);
      return;
    case Target::InPlace:
      write_in_place(t.path, write);
      return;
    case Target::Replace: {
      ReplacingFile f(path, t.path, t.exists, t.mode);
      f.write_at(0, write);
      f.commit();
      return;
    }
  }
}

}  // namespace cdtgpu
