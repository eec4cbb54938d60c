// PNG output through libpng (8-bit RGBA), whole-or-nothing like every other output.
// Usage: write_png_file("tin.png", width, height, rgba);   // rgba: height rows of width * 4 bytes, top first
#pragma once
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace cdtgpu {

void write_png(uint64_t width, uint64_t height, const std::vector<uint8_t>& rgba, std::ostream& out);
void write_png_file(const std::string& path, uint64_t width, uint64_t height,
                    const std::vector<uint8_t>& rgba);

}  // namespace cdtgpu
