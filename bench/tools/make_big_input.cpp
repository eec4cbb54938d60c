// make_big_input: a LAS 1.2 file of N uniform ground points (point format 0, millimetres) and a shapefile of
// non-crossing contour-like lines with M vertices in all, written on all cores, for end-to-end runs at sizes
// the bench's own writers take minutes for (1B points: 20 GB of LAS in seconds). Tooling, not the product.
//
//   cdtgpu-make-big-input OUT_DIR POINTS LINE_VERTICES [VERTICES_PER_LINE=2000] [SEED=1]
//   -> OUT_DIR/points.las, OUT_DIR/contours_K.{shp,shx,dbf} (K = 1, 2, ...: a .shp holds at most 4 GB, so at
//      most 100M line vertices a file)
#include <fcntl.h>
#include <shapefil.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr double kX0 = 500000, kY0 = 6000000, kSide = 100000;  // a 100 km square, UTM-like metres

template <class T>
void put(std::vector<char>& h, size_t at, T v) {
  std::memcpy(h.data() + at, &v, sizeof v);
}

void write_las(const std::string& path, uint64_t n, uint64_t seed) {
  std::vector<char> h(227, 0);
  std::memcpy(h.data(), "LASF", 4);
  h[24] = 1, h[25] = 2;                       // version 1.2
  put<uint16_t>(h, 94, 227);                  // header size
  put<uint32_t>(h, 96, 227);                  // offset to the points
  put<uint8_t>(h, 104, 0);                    // point format 0
  put<uint16_t>(h, 105, 20);                  // record length
  put<uint32_t>(h, 107, uint32_t(n));         // point count
  put<uint32_t>(h, 111, uint32_t(n));         // of return 1
  for (int k = 0; k < 3; ++k) put<double>(h, 131 + 8 * k, 0.001);  // scale
  put<double>(h, 155, kX0), put<double>(h, 163, kY0), put<double>(h, 171, 0.0);  // offset
  put<double>(h, 179, kX0 + kSide), put<double>(h, 187, kX0);                   // max x, min x
  put<double>(h, 195, kY0 + kSide), put<double>(h, 203, kY0);                   // max y, min y
  put<double>(h, 211, 200.0), put<double>(h, 219, 0.0);                         // max z, min z
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0 || ::pwrite(fd, h.data(), h.size(), 0) != ssize_t(h.size()))
    throw std::runtime_error("cannot write " + path);
  // 32 ranges, each with a generator of its own and a thread: the same files on every host. With a range a
  // hardware thread, a 16-thread host wrote other points than a 32-thread one (1B + 250M: 82 duplicates merged
  // against 79; session 68).
  constexpr unsigned threads = 32;
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      const uint64_t first = n * t / threads, last = n * (t + 1) / threads;
      std::mt19937_64 rng(seed * 1000003 + t);
      std::uniform_int_distribution<int32_t> xy(0, int32_t(kSide * 1000)), z(0, 200000);
      std::vector<char> buf;
      for (uint64_t i = first; i < last;) {
        const uint64_t count = std::min<uint64_t>(last - i, 1 << 20);
        buf.assign(count * 20, 0);
        for (uint64_t k = 0; k < count; ++k) {
          char* p = buf.data() + k * 20;
          const int32_t X = xy(rng), Y = xy(rng), Z = z(rng);
          std::memcpy(p, &X, 4), std::memcpy(p + 4, &Y, 4), std::memcpy(p + 8, &Z, 4);
          p[14] = 9;  // return 1 of 1
          p[15] = 2;  // ground
        }
        if (::pwrite(fd, buf.data(), buf.size(), off_t(227 + 20 * i)) != ssize_t(buf.size())) std::abort();
        i += count;
      }
    });
  for (auto& th : pool) th.join();
  ::close(fd);
}

// Lines in bands of y, one a band, so that they never cross; x across the square, y jittered within the band.
void write_lines(const std::string& dir, uint64_t vertices, uint64_t per_line, uint64_t seed) {
  const uint64_t lines = std::max<uint64_t>(1, vertices / per_line);
  const uint64_t per_file = std::max<uint64_t>(1, 100'000'000 / per_line);
  SHPHandle shp = nullptr;
  DBFHandle dbf = nullptr;
  auto close = [&] {
    if (shp) SHPClose(shp), DBFClose(dbf);
  };
  std::mt19937_64 rng(seed ^ 0x9E3779B97F4A7C15ULL);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  std::vector<double> x(per_line), y(per_line), z(per_line);
  const double band = kSide / double(lines);
  for (uint64_t i = 0; i < lines; ++i) {
    if (i % per_file == 0) {
      close();
      const std::string base = dir + "/contours_" + std::to_string(i / per_file + 1);
      shp = SHPCreate((base + ".shp").c_str(), SHPT_ARCZ);
      dbf = DBFCreate((base + ".dbf").c_str());
      if (!shp || !dbf || DBFAddField(dbf, "ELEV", FTDouble, 12, 3) < 0)
        throw std::runtime_error("cannot create " + base);
    }
    const double centre = kY0 + (double(i) + 0.5) * band, elev = 100 + 0.001 * double(i % 100000);
    for (uint64_t j = 0; j < per_line; ++j) {
      x[j] = std::round((kX0 + kSide * (double(j) + 0.5) / double(per_line)) * 1000) / 1000;
      y[j] = std::round((centre + jitter(rng) * band) * 1000) / 1000;
      z[j] = elev;
    }
    SHPObject* o = SHPCreateSimpleObject(SHPT_ARCZ, int(per_line), x.data(), y.data(), z.data());
    const int record = SHPWriteObject(shp, -1, o);
    SHPDestroyObject(o);
    if (record < 0 || !DBFWriteDoubleAttribute(dbf, record, 0, elev)) throw std::runtime_error("cannot write " + dir);
  }
  close();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s OUT_DIR POINTS LINE_VERTICES [VERTICES_PER_LINE] [SEED]\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const uint64_t n = std::stoull(argv[2]), m = std::stoull(argv[3]);
  const uint64_t per_line = argc > 4 ? std::stoull(argv[4]) : 2000, seed = argc > 5 ? std::stoull(argv[5]) : 1;
  if (n >= (uint64_t(1) << 32)) throw std::runtime_error("LAS 1.2 counts points in 32 bits");
  std::thread las([&] { write_las(dir + "/points.las", n, seed); });
  if (m > 0) write_lines(dir, m, per_line, seed);
  las.join();
  return 0;
}
