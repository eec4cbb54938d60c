// libpng with a write callback into the std::ostream of write_file_atomically; libpng reports errors by
// longjmp, so everything with a destructor lives outside the setjmp frame.
#include "io/write_png.hpp"

#include <png.h>

#include <csetjmp>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace cdtgpu {

namespace {

void on_write(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::ostream*>(png_get_io_ptr(png));
  out->write(reinterpret_cast<const char*>(data), std::streamsize(n));
}
void on_flush(png_structp png) { static_cast<std::ostream*>(png_get_io_ptr(png))->flush(); }

// Returns an error message, empty on success.
const char* encode(png_structp png, png_infop info, uint64_t width, uint64_t height, const uint8_t* rgba,
                   std::ostream* out) {
  if (setjmp(png_jmpbuf(png))) return "libpng failed to encode the image";
  png_set_write_fn(png, out, on_write, on_flush);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB_ALPHA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (uint64_t row = 0; row < height; ++row) png_write_row(png, rgba + row * width * 4);
  png_write_end(png, nullptr);
  return "";
}

}  // namespace

void write_png(uint64_t width, uint64_t height, const std::vector<uint8_t>& rgba, std::ostream& out) {
  if (width == 0 || height == 0 || width > 0x7fffffff || height > 0x7fffffff)
    throw std::runtime_error("PNG size " + std::to_string(width) + " x " + std::to_string(height) +
                             " is not valid");
  if (rgba.size() != width * height * 4) throw std::runtime_error("PNG pixel buffer has the wrong size");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error("libpng: cannot create a write structure");
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error("libpng: cannot create an info structure");
  }
  const std::string error = encode(png, info, width, height, rgba.data(), &out);
  png_destroy_write_struct(&png, &info);
  if (!error.empty()) throw std::runtime_error(error);
  if (!out) throw std::runtime_error("write failed");
}

void write_png_file(const std::string& path, uint64_t width, uint64_t height,
                    const std::vector<uint8_t>& rgba) {
  write_file_atomically(path, [&](std::ostream& out) { write_png(width, height, rgba, out); });
}

}  // namespace cdtgpu
