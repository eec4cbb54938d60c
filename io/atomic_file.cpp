// Whole-or-nothing output: write to "<path>.tmp-<pid>" in the target's folder (so the rename stays on one
// file system and is atomic), then rename over the target. Any exception removes the temporary file.
#include "io/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

namespace cdtgpu {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (path == "-") {
    write(std::cout);
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("<stdout>: write failed");
    return;
  }
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  std::ofstream out;
  // A large buffer: the writers hand over big blocks, but small writes (headers) should not each hit the OS.
  static thread_local char buffer[1 << 16];
  out.rdbuf()->pubsetbuf(buffer, sizeof buffer);
  out.open(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot create " + tmp + ": " + std::strerror(errno));
  try {
    out.exceptions(std::ios::badbit | std::ios::failbit);
    write(out);
    out.flush();
    out.close();
  } catch (const std::ios_base::failure& e) {
    const int err = errno;
    out.exceptions(std::ios::goodbit);
    out.close();
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path + ": write failed: " + (err ? std::strerror(err) : e.what()));
  } catch (...) {
    out.exceptions(std::ios::goodbit);
    out.close();
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw std::runtime_error(path + ": cannot rename " + tmp + " into place: " + ec.message());
  }
}

}  // namespace cdtgpu
