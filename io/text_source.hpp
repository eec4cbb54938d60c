// A text input as one contiguous view, and the split of that view into pieces parsed on all cores.
//
//   TextSource src = TextSource::open("dem.xyz");          // memory-mapped; stdin and pipes are read whole
//   parse_chunks(src.text(), [&](size_t k, Chunk c) { ... parse lines [c.begin, c.end) ... });
//
// Readers keep their error messages exact: each chunk knows the line number it starts at, and when several
// chunks fail, the failure earliest in the file is the one reported (as a sequential reader would).
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

#include "core/model.hpp"

namespace cdtgpu {

class TextSource {
 public:
  // Maps a regular file; anything else (FIFO, character device) is read whole. Throws InputError naming
  // the path when it cannot be opened or read.
  static TextSource open(const std::string& path);
  // Reads a stream whole (stdin, tests).
  static TextSource read(std::istream& in, const std::string& name);

  // Without a leading UTF-8 byte order mark (spreadsheet exports start with one).
  std::string_view text() const;

  TextSource() = default;
  TextSource(TextSource&& o) noexcept;
  TextSource& operator=(TextSource&& o) noexcept;
  TextSource(const TextSource&) = delete;
  TextSource& operator=(const TextSource&) = delete;
  ~TextSource();

 private:
  const char* map_ = nullptr;  // mmap'd bytes, or null when the text lives in owned_
  size_t size_ = 0;
  std::string owned_;
};

// Byte ranges of `text` that end at line ends ('\n') and hold about `target` bytes each (the last one may be
// shorter), with the line number each one starts at (the first line is `first_line`).
struct Chunk {
  size_t begin = 0, end = 0;
  uint64_t first_line = 1;
};
std::vector<Chunk> split_lines(std::string_view text, size_t target, uint64_t first_line = 1);

// The chunk size parse_chunks uses: a few pieces per core, none smaller than 256 KiB.
size_t chunk_bytes(size_t text_size);

// Runs `parse(k, chunk)` for every chunk of split_lines(text, chunk_bytes(...)) on all cores. If any throw,
// rethrows the exception of the lowest-numbered chunk that threw (the earliest in the file).
void parse_chunks(const std::vector<Chunk>& chunks, const std::function<void(size_t, const Chunk&)>& parse);

// An empty InputSet for one chunk's results, read as `in` is read (its reading flags): its sources list names
// `name` at index `source`, so that errors raised while adding geometry to it name the file.
InputSet chunk_part(const InputSet& in, uint32_t source, const std::string& name);
// Appends the parts to `in` in order (points, lines, repair counts), as if read one after another.
void append_parts(InputSet& in, std::vector<InputSet>& parts);

}  // namespace cdtgpu
