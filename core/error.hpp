// Errors with context, caught once in cli/ and turned into a message and an exit code.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

namespace cdtgpu {

// Bad input: the message names the file and, where known, the record or line. Exit code 2.
struct InputError : std::runtime_error {
  InputError(const std::string& file, uint64_t record, const std::string& what)
      : std::runtime_error(file + (record ? ":" + std::to_string(record) : std::string()) + ": " + what),
        file(file), record(record) {}
  std::string file;
  uint64_t record;  // 0 when the error is about the whole file
};

// A usage error (bad option value, unknown format). Exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace cdtgpu
