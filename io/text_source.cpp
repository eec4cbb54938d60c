// Text inputs mapped into memory and cut at line ends, so that the readers parse on all cores (issue 16: the
// line-by-line getline readers ran at ~0.2 GB/s and were the largest stage of a 2M-point run).
#include "io/text_source.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <iterator>
#include <mutex>
#include <thread>

#include "core/error.hpp"
#include "core/touched.hpp"
#include "core/uninit.hpp"

namespace cdtgpu {

namespace {

std::string_view without_bom(std::string_view s) {
  if (s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);
  return s;
}

}  // namespace

TextSource TextSource::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    throw InputError(path, 0, std::string("cannot open: ") + std::strerror(err));
  }
  TextSource src;
  if (S_ISREG(st.st_mode) && st.st_size > 0) {
    void* p = ::mmap(nullptr, size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (p != MAP_FAILED) {
      ::madvise(p, size_t(st.st_size), MADV_WILLNEED);
      src.map_ = static_cast<const char*>(p);
      src.size_ = size_t(st.st_size);
      ::close(fd);
      return src;
    }
  }
  // Pipes, devices, process substitution, or a file that cannot be mapped: read it whole.
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path, 0, std::string("read error: ") + std::strerror(err));
    }
    src.owned_.append(buf, size_t(n));
  }
  ::close(fd);
  return src;
}

TextSource TextSource::read(std::istream& in, const std::string& name) {
  TextSource src;
  src.owned_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(name, 0, "read error");
  return src;
}

std::string_view TextSource::text() const {
  return without_bom(map_ ? std::string_view(map_, size_) : std::string_view(owned_));
}

TextSource::TextSource(TextSource&& o) noexcept
    : map_(std::exchange(o.map_, nullptr)), size_(std::exchange(o.size_, 0)), owned_(std::move(o.owned_)) {}

TextSource& TextSource::operator=(TextSource&& o) noexcept {
  if (this != &o) {
    if (map_) ::munmap(const_cast<char*>(map_), size_);
    map_ = std::exchange(o.map_, nullptr);
    size_ = std::exchange(o.size_, 0);
    owned_ = std::move(o.owned_);
  }
  return *this;
}

TextSource::~TextSource() {
  if (map_) ::munmap(const_cast<char*>(map_), size_);
}

size_t chunk_bytes(size_t text_size) {
  const size_t parts = 4 * std::max(1u, std::thread::hardware_concurrency());
  return std::max<size_t>(256 << 10, (text_size + parts - 1) / parts);
}

std::vector<Chunk> split_lines(std::string_view text, size_t target, uint64_t first_line) {
  std::vector<Chunk> chunks;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = std::min(text.size(), begin + std::max<size_t>(target, 1));
    if (end < text.size()) {
      const void* nl = std::memchr(text.data() + end - 1, '\n', text.size() - (end - 1));
      end = nl ? size_t(static_cast<const char*>(nl) - text.data()) + 1 : text.size();
    }
    chunks.push_back({begin, end, 0});
    begin = end;
  }
  // Line numbers: every chunk counts its own line ends, then a running sum.
  std::vector<uint64_t> lines(chunks.size());
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t k) {
    lines[k] = uint64_t(std::count(text.data() + chunks[k].begin, text.data() + chunks[k].end, '\n'));
  });
  uint64_t line = first_line;
  for (size_t k = 0; k < chunks.size(); ++k) {
    chunks[k].first_line = line;
    line += lines[k];
  }
  return chunks;
}

void parse_chunks(const std::vector<Chunk>& chunks, const std::function<void(size_t, const Chunk&)>& parse) {
  std::vector<std::exception_ptr> errors(chunks.size());
  tbb::parallel_for(size_t(0), chunks.size(), [&](size_t k) {
    try {
      parse(k, chunks[k]);
    } catch (...) {
      errors[k] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

InputSet chunk_part(const InputSet& in, uint32_t source, const std::string& name) {
  InputSet part;
  part.nan_for_missing_z = in.nan_for_missing_z;
  part.sources.resize(size_t(source) + 1);
  part.sources[source] = name;
  return part;
}

void append_parts(InputSet& in, std::vector<InputSet>& parts) {
  std::vector<size_t> at(parts.size() + 1, in.points.size());
  size_t lines = in.lines.size();
  for (size_t k = 0; k < parts.size(); ++k) {
    at[k + 1] = at[k] + parts[k].points.size();
    lines += parts[k].lines.size();
  }
  resize_unwritten(in.points, at.back());  // written on all cores, the earlier inputs kept
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
    std::copy(parts[k].points.begin(), parts[k].points.end(), in.points.begin() + std::ptrdiff_t(at[k]));
    free_storage(parts[k].points);
  });
  in.lines.reserve(lines);
  for (InputSet& part : parts) {
    std::move(part.lines.begin(), part.lines.end(), std::back_inserter(in.lines));
    free_storage(part.lines);
    Repairs& r = in.repairs;
    r.repeated_vertices += part.repairs.repeated_vertices;
    r.rings_closed += part.repairs.rings_closed;
    r.degenerate_lines += part.repairs.degenerate_lines;
    r.null_shapes += part.repairs.null_shapes;
    r.nodata_cells += part.repairs.nodata_cells;
  }
}

}  // namespace cdtgpu
