// Read-only files for the shapefile reader and for shapelib (through SAHooks): mapped from disk, or held in
// memory under a path, so that the fuzz target hands the reader its bytes without a trip through the file
// system (fuzz/harness.hpp). A path held in memory hides a file of that name on disk.
//
//   files::put_memory_file("/mem/a.shp", bytes);            // now a regular file to every function below
//   files::File* f = files::open("/mem/a.shp");             // nullptr when there is no such file
//   std::string_view all = f->bytes();  files::close(f);
//   SAHooks hooks = files::hooks(on_error);                 // SHPOpenLL / DBFOpenLL read the same way
#pragma once
#include <shapefil.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace cdtgpu::files {

// One mapping of a file on disk, shared by the Files open on it at once (see open()).
struct Mapping;

// An open file: its bytes and a read position for shapelib.
struct File {
  const char* data = nullptr;
  size_t size = 0, pos = 0;
  std::shared_ptr<const Mapping> mapping;      // unmapped when the last File on it closes
  std::string owned;                           // an empty or unmappable file's bytes
  std::shared_ptr<const std::string> memory;   // a file held in memory stays alive while open
  std::string_view bytes() const { return {data, size}; }
};

// Holds `bytes` under `path` (replacing what was there) until remove_memory_file.
void put_memory_file(const std::string& path, std::string bytes);
void remove_memory_file(const std::string& path);

// A file held in memory, or a regular file on disk.
bool is_file(const std::string& path);
// Opens for reading: nullptr (errno set) when there is no such file or it cannot be read. Files open on the
// same unchanged file at once share one mapping: the shapefile reader opens a handle per range of records on
// every core, and a mapping each (mmap, page faults and munmap under the process's one memory-map lock) kept
// 16 cores at 325 MB/s.
File* open(const std::string& path);
void close(File* f);
// Owns an open file.
struct Closer {
  void operator()(File* f) const { close(f); }
};
using Open = std::unique_ptr<File, Closer>;

// shapelib hooks over open()/close(), read-only; `error` gets shapelib's messages.
SAHooks hooks(void (*error)(const char*));

}  // namespace cdtgpu::files
