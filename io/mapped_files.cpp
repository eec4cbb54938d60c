// Read-only files, mapped from disk or held in memory; see mapped_files.hpp. Mapping, not stdio: every
// SHPReadObject was a seek and a read system call, and a 2M-point shapefile took 4 s to read on the H100
// machine.
#include "io/mapped_files.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>

namespace cdtgpu::files {
namespace {

std::mutex memory_mutex;
std::map<std::string, std::shared_ptr<const std::string>>& memory_files() {
  static std::map<std::string, std::shared_ptr<const std::string>> m;
  return m;
}

std::shared_ptr<const std::string> in_memory(const std::string& path) {
  std::lock_guard lock(memory_mutex);
  auto& m = memory_files();
  if (m.empty()) return nullptr;
  auto it = m.find(path);
  return it == m.end() ? nullptr : it->second;
}

SAFile hook_open(const char* name, const char* access) {
  if (std::strpbrk(access, "wa+")) return nullptr;  // the reader never writes
  return reinterpret_cast<SAFile>(open(name));
}

SAOffset hook_read(void* p, SAOffset size, SAOffset n, SAFile file) {
  auto* f = reinterpret_cast<File*>(file);
  if (size == 0) return 0;
  const SAOffset items = std::min<SAOffset>(n, (f->size - std::min(f->pos, f->size)) / size);
  std::memcpy(p, f->data + f->pos, items * size);
  f->pos += items * size;
  return items;
}

SAOffset hook_write(void*, SAOffset, SAOffset, SAFile) { return 0; }

SAOffset hook_seek(SAFile file, SAOffset offset, int whence) {
  auto* f = reinterpret_cast<File*>(file);
  const size_t base = whence == SEEK_SET ? 0 : whence == SEEK_CUR ? f->pos : f->size;
  f->pos = base + offset;
  return 0;
}

SAOffset hook_tell(SAFile file) { return reinterpret_cast<File*>(file)->pos; }
int hook_flush(SAFile) { return 0; }
int hook_close(SAFile file) {
  close(reinterpret_cast<File*>(file));
  return 0;
}

}  // namespace

void put_memory_file(const std::string& path, std::string bytes) {
  auto held = std::make_shared<const std::string>(std::move(bytes));
  std::lock_guard lock(memory_mutex);
  memory_files()[path] = std::move(held);
}

void remove_memory_file(const std::string& path) {
  std::lock_guard lock(memory_mutex);
  memory_files().erase(path);
}

bool is_file(const std::string& path) {
  if (in_memory(path)) return true;
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

File* open(const std::string& path) {
  if (auto held = in_memory(path)) {
    auto* f = new File;
    f->data = held->data();
    f->size = held->size();
    f->memory = std::move(held);
    return f;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return nullptr;
  struct stat st {};
  auto* f = new File;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
    void* p = ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (p != MAP_FAILED) {
      f->data = static_cast<const char*>(p);
      f->size = size_t(st.st_size);
      f->mapped = true;
    }
  }
  if (!f->mapped) {  // not mappable: read it whole
    char buf[1 << 16];
    for (ssize_t n; (n = ::read(fd, buf, sizeof buf)) != 0;) {
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        const int e = errno;
        ::close(fd);
        delete f;
        errno = e;
        return nullptr;
      }
      f->owned.append(buf, size_t(n));
    }
    f->data = f->owned.data();
    f->size = f->owned.size();
  }
  ::close(fd);
  return f;
}

void close(File* f) {
  if (!f) return;
  if (f->mapped) ::munmap(const_cast<char*>(f->data), f->size);
  delete f;
}

SAHooks hooks(void (*error)(const char*)) {
  SAHooks h;
  SASetupDefaultHooks(&h);
  h.FOpen = hook_open;
  h.FRead = hook_read;
  h.FWrite = hook_write;
  h.FSeek = hook_seek;
  h.FTell = hook_tell;
  h.FFlush = hook_flush;
  h.FClose = hook_close;
  h.Error = error;
  return h;
}

}  // namespace cdtgpu::files
