// Errors with context, caught once in cli/ and turned into a message and an exit code.
#pragma once
#include <charconv>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace cdtgpu {

// Bad input: the message names the file and, where known, the record or line. Exit code 2.
struct InputError : std::runtime_error {
  InputError(const std::string& file, uint64_t record, const std::string& what)
      : std::runtime_error(message(file, record, what)), file(file), record(record), detail(what) {}
  std::string file;
  uint64_t record;     // 0 when the error is about the whole file
  std::string detail;  // the message without the file and record

 private:
  // Built with += : GCC 12 gives a false -Wrestrict warning on `":" + std::to_string(n)` here.
  static std::string message(const std::string& file, uint64_t record, const std::string& what) {
    std::string m = file;
    if (record) {
      m += ':';
      m += std::to_string(record);
    }
    m += ": ";
    m += what;
    return m;
  }
};

// A number as messages write it: the shortest text that reads back to the same double ("1e-09", "0.5", "250000"),
// never std::to_string's six fixed decimals ("0.000000").
inline std::string number_text(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// A usage error (bad option value, unknown format). Exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace cdtgpu
