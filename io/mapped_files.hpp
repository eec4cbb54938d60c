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

// An open file: its bytes and a read position for shapelib.
struct File {
  const char* data = nullptr;
  size_t size = 0, pos = 0;
  bool mapped = false;                         // munmap on close
  std::string owned;                           // an empty or unmappable file's bytes
  std::shared_ptr<const std::string> memory;   // a file held in memory stays alive while open
  std::string_view bytes() const { return {data, size}; }
};

// Holds `bytes` under `path` (replacing what was there) until remove_memory_file.
void put_memory_file(const std::string& path, std::string bytes);
void remove_memory_file(const std::string& path);

// A file held in memory, or a regular file on disk.
bool is_file(const std::string& path);
// Opens for reading: nullptr (errno set) when there is no such file or it cannot be read.
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
