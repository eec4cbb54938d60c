// A small LAS writer for the tests and the LAS bench tool, written from the ASPRS LAS 1.4 specification (R15,
// 2019): public header block (table 3; 227 bytes for 1.0-1.2, 235 for 1.3, 375 for 1.4), VLRs (table 4, 54-byte
// headers), EVLRs (table 5, 60-byte headers) and point data record formats 0-10 (tables 7-17). Every field the
// reader skips is filled with a value of its own (intensity, GPS time, colours, wave packets), so a reader that
// took a field from the wrong byte would see it.
//
//   LasFile f;  f.minor = 4;  f.format = 6;
//   f.points.push_back({.X = 1234, .Y = 5678, .Z = 90, .cls = 2});
//   std::string bytes = las_bytes(f);
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace cdtgpu::test {

struct LasPoint {
  int32_t X = 0, Y = 0, Z = 0;
  uint8_t ret = 1, returns = 1;  // return number, number of returns
  uint8_t cls = 1;               // formats 0-5 store the low 5 bits
  bool withheld = false, synthetic = false, key_point = false, overlap = false;
};

struct Vlr {
  std::string user;  // up to 16 bytes
  uint16_t id = 0;
  std::string data;
};

struct LasFile {
  int major = 1, minor = 4;
  int format = 0;
  uint16_t extra_bytes = 0;  // bytes after each record's own fields
  double scale[3] = {0.01, 0.01, 0.001};
  double offset[3] = {500000, 6000000, 0};
  std::vector<LasPoint> points;
  std::vector<Vlr> vlrs, evlrs;  // evlrs: LAS 1.4 only
  // Point counts as written: -1 gives what the specification asks (1.4: legacy count 0 for formats 6-10).
  int64_t legacy_count = -1, count64 = -1;
};

// The OGC WKT VLR (record 2112) and the GeoKeyDirectory VLR (34735) with one key (3072 projected, 2048
// geographic) holding an EPSG code.
inline Vlr wkt_vlr(const std::string& wkt) { return {"LASF_Projection", 2112, wkt + '\0'}; }
inline Vlr geokeys_vlr(uint16_t key, uint16_t code) {
  const uint16_t model = key == 3072 ? 1 : 2;  // GTModelTypeGeoKey: projected or geographic
  const uint16_t keys[] = {1, 1, 0, 2, 1024, 0, 1, model, key, 0, 1, code};
  return {"LASF_Projection", 34735, std::string(reinterpret_cast<const char*>(keys), sizeof keys)};
}

inline int las_format_size(int format) {
  static constexpr int kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return kSizes[format];
}

namespace detail {
template <typename T>
void put(std::string& s, size_t at, T v) {
  std::memcpy(s.data() + at, &v, sizeof v);
}
inline void put_text(std::string& s, size_t at, const std::string& t, size_t n) {
  std::memcpy(s.data() + at, t.data(), std::min(t.size(), n));
}
}  // namespace detail

inline std::string las_record(const LasFile& f, const LasPoint& p, size_t index) {
  using detail::put;
  const int size = las_format_size(f.format);
  std::string r(size_t(size) + f.extra_bytes, '\0');
  put<int32_t>(r, 0, p.X);
  put<int32_t>(r, 4, p.Y);
  put<int32_t>(r, 8, p.Z);
  put<uint16_t>(r, 12, uint16_t(1000 + index));  // intensity
  const bool edge = index % 2, direction = index % 3 == 0;
  if (f.format <= 5) {
    r[14] = char((p.ret & 7) | (p.returns & 7) << 3 | direction << 6 | edge << 7);
    r[15] = char((p.cls & 31) | p.synthetic << 5 | p.key_point << 6 | p.withheld << 7);
    r[16] = char(-12);                               // scan angle rank
    r[17] = char(0x5A);                              // user data
    put<uint16_t>(r, 18, uint16_t(7 + index));       // point source ID
    size_t at = 20;
    if (f.format == 1 || f.format == 3 || f.format == 4 || f.format == 5) {
      put<double>(r, at, 1e5 + double(index));      // GPS time
      at += 8;
    }
    if (f.format == 2 || f.format == 3 || f.format == 5) {
      for (int c = 0; c < 3; ++c) put<uint16_t>(r, at + 2 * c, uint16_t(0xABC0 + c));
      at += 6;
    }
    if (f.format == 4 || f.format == 5) std::memset(r.data() + at, 0x77, 29);  // wave packet
  } else {
    r[14] = char((p.ret & 15) | (p.returns & 15) << 4);
    r[15] = char(p.synthetic | p.key_point << 1 | p.withheld << 2 | p.overlap << 3 | 2 << 4 | direction << 6 |
                 edge << 7);
    r[16] = char(p.cls);
    r[17] = char(0x5A);
    put<int16_t>(r, 18, int16_t(-1500));             // scan angle
    put<uint16_t>(r, 20, uint16_t(7 + index));
    put<double>(r, 22, 1e5 + double(index));
    size_t at = 30;
    if (f.format == 7 || f.format == 8 || f.format == 10) {
      for (int c = 0; c < 3; ++c) put<uint16_t>(r, at + 2 * c, uint16_t(0xABC0 + c));
      at += 6;
    }
    if (f.format == 8 || f.format == 10) {
      put<uint16_t>(r, at, uint16_t(0xBEEF));        // NIR
      at += 2;
    }
    if (f.format == 9 || f.format == 10) std::memset(r.data() + at, 0x77, 29);
  }
  std::memset(r.data() + size, 0xEE, f.extra_bytes);
  return r;
}

inline std::string las_bytes(const LasFile& f) {
  using detail::put;
  const uint16_t header_size = f.minor >= 4 ? 375 : f.minor == 3 ? 235 : 227;
  std::string vlr_bytes;
  for (const Vlr& v : f.vlrs) {
    std::string h(54, '\0');
    detail::put_text(h, 2, v.user, 16);
    put<uint16_t>(h, 18, v.id);
    put<uint16_t>(h, 20, uint16_t(v.data.size()));
    detail::put_text(h, 22, "cdtgpu test", 32);
    vlr_bytes += h + v.data;
  }
  const uint64_t n = f.points.size();
  const uint16_t record_length = uint16_t(las_format_size(f.format) + f.extra_bytes);
  const uint32_t point_offset = uint32_t(header_size + vlr_bytes.size());
  std::string h(header_size, '\0');
  detail::put_text(h, 0, "LASF", 4);
  put<uint16_t>(h, 4, 42);                                   // file source ID
  put<uint16_t>(h, 6, uint16_t(f.format >= 6 ? 0x11 : 0x01));  // GPS standard time; WKT bit for 6-10
  h[24] = char(f.major);
  h[25] = char(f.minor);
  detail::put_text(h, 26, "cdtgpu tests", 32);
  detail::put_text(h, 58, "tests/las_writer.hpp", 32);
  put<uint16_t>(h, 90, 330);
  put<uint16_t>(h, 92, 2026);
  put<uint16_t>(h, 94, header_size);
  put<uint32_t>(h, 96, point_offset);
  put<uint32_t>(h, 100, uint32_t(f.vlrs.size()));
  h[104] = char(f.format);
  put<uint16_t>(h, 105, record_length);
  const bool legacy_allowed = f.format < 6 && n <= std::numeric_limits<uint32_t>::max();
  const uint32_t legacy = uint32_t(f.legacy_count >= 0 ? f.legacy_count : legacy_allowed ? int64_t(n) : 0);
  put<uint32_t>(h, 107, legacy);
  uint64_t by_return[15] = {};
  for (const LasPoint& p : f.points)
    if (p.ret >= 1 && p.ret <= 15) ++by_return[p.ret - 1];
  for (int k = 0; k < 5; ++k) put<uint32_t>(h, 111 + 4 * k, legacy_allowed ? uint32_t(by_return[k]) : 0);
  for (int a = 0; a < 3; ++a) {
    put<double>(h, 131 + 8 * a, f.scale[a]);
    put<double>(h, 155 + 8 * a, f.offset[a]);
  }
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (size_t i = 0; i < f.points.size(); ++i) {
    const int32_t v[3] = {f.points[i].X, f.points[i].Y, f.points[i].Z};
    for (int a = 0; a < 3; ++a) {
      const double c = double(v[a]) * f.scale[a] + f.offset[a];
      lo[a] = i ? std::min(lo[a], c) : c;
      hi[a] = i ? std::max(hi[a], c) : c;
    }
  }
  for (int a = 0; a < 3; ++a) {
    put<double>(h, 179 + 16 * a, hi[a]);
    put<double>(h, 187 + 16 * a, lo[a]);
  }
  std::string body;
  body.reserve(n * record_length);
  for (size_t i = 0; i < f.points.size(); ++i) body += las_record(f, f.points[i], i);
  if (f.minor >= 4) {
    put<uint64_t>(h, 227, 0);  // no waveform data packets
    put<uint64_t>(h, 235, f.evlrs.empty() ? 0 : point_offset + body.size());
    put<uint32_t>(h, 243, uint32_t(f.evlrs.size()));
    put<uint64_t>(h, 247, f.count64 >= 0 ? uint64_t(f.count64) : n);
    for (int k = 0; k < 15; ++k) put<uint64_t>(h, 255 + 8 * k, by_return[k]);
  } else if (f.minor == 3) {
    put<uint64_t>(h, 227, 0);
  }
  std::string evlr_bytes;
  for (const Vlr& v : f.evlrs) {
    std::string e(60, '\0');
    detail::put_text(e, 2, v.user, 16);
    put<uint16_t>(e, 18, v.id);
    put<uint64_t>(e, 20, v.data.size());
    detail::put_text(e, 28, "cdtgpu test", 32);
    evlr_bytes += e + v.data;
  }
  return h + vlr_bytes + body + evlr_bytes;
}

}  // namespace cdtgpu::test
