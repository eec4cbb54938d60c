// A text buffer for the GIS writers (LandXML, 2DM, ASCII grid, contours): numbers with std::to_chars (the
// shortest digits that read back to the same double), handed to the stream in 1 MiB blocks.
#pragma once
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace cdtgpu {

class TextOut {
 public:
  explicit TextOut(std::ostream& out) : out_(out), buf_(1 << 20) {}
  TextOut(const TextOut&) = delete;
  TextOut& operator=(const TextOut&) = delete;

  void flush() {
    out_.write(buf_.data(), std::streamsize(n_));
    n_ = 0;
    if (!out_) throw std::runtime_error("write failed");
  }
  TextOut& text(std::string_view s) {
    if (n_ + s.size() > buf_.size()) flush();
    if (s.size() > buf_.size()) {
      out_.write(s.data(), std::streamsize(s.size()));
      if (!out_) throw std::runtime_error("write failed");
      return *this;
    }
    std::memcpy(buf_.data() + n_, s.data(), s.size());
    n_ += s.size();
    return *this;
  }
  TextOut& ch(char c) {
    if (n_ + 1 > buf_.size()) flush();
    buf_[n_++] = c;
    return *this;
  }
  // Shortest round-trip text. Plain std::to_chars picks scientific whenever it is shorter ("5e+05" for
  // 500000); civil and hydraulic tools expect coordinates in fixed notation, so magnitudes from 1e-4 to 1e16
  // are written fixed (still the shortest digits that read back exactly), others as to_chars chooses.
  TextOut& number(double v) {
    if (n_ + kMaxNumberChars > buf_.size()) flush();
    n_ = size_t(put_number(buf_.data() + n_, v) - buf_.data());
    return *this;
  }
  // The most characters number(double) writes.
  static constexpr size_t kMaxNumberChars = 48;
  // number(double)'s text at p (room for kMaxNumberChars); returns its end. For writers that format on
  // several threads into buffers of their own.
  static char* put_number(char* p, double v) {
    const double a = std::fabs(v);
    if (a >= 1e-4 && a < 1e16) return std::to_chars(p, p + kMaxNumberChars, v, std::chars_format::fixed).ptr;
    return std::to_chars(p, p + kMaxNumberChars, v).ptr;
  }
  TextOut& number(uint64_t v) { return chars(v); }
  TextOut& number(int64_t v) { return chars(v); }

 private:
  template <class T>
  TextOut& chars(T v) {
    if (n_ + 32 > buf_.size()) flush();
    n_ = size_t(std::to_chars(buf_.data() + n_, buf_.data() + buf_.size(), v).ptr - buf_.data());
    return *this;
  }
  std::ostream& out_;
  std::vector<char> buf_;
  size_t n_ = 0;
};

}  // namespace cdtgpu
