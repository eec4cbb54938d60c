// LAS reader: the file is mapped (io/mapped_files), the header and (E)VLRs checked against its size, then the
// point records are decoded on all cores in two passes over ranges of records: the first applies the filters
// and counts (per class, kept and skipped), the second writes the kept points straight into their place in
// InputSet::points, so the output is in file order without a copy.
//
// Fields per record (LAS 1.4 R15, tables 7-17): X Y Z int32 at bytes 0, 4, 8 in every format. Formats 0-5:
// byte 14 return number (bits 0-2) and number of returns (bits 3-5), byte 15 classification (bits 0-4) with
// the withheld flag (bit 7), in LAS 1.0 files too (as PDAL, LAStools and laspy read them). Formats 6-10:
// byte 14 return number (bits 0-3) and number of returns (bits 4-7), byte 15 flags (withheld: bit 2), byte 16
// the class (0-255).
#include "io/read_las.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "core/repair.hpp"
#include "core/touched.hpp"
#include "io/mapped_files.hpp"
#include "io/read_share.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

static_assert(std::endian::native == std::endian::little, "LAS is little-endian; the reader copies fields as they are");

template <typename T>
T get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Bytes the public header has at least, by minor version (1.0-1.2: 227, 1.3: 235, 1.4: 375).
uint16_t min_header_size(int minor) { return minor >= 4 ? 375 : minor == 3 ? 235 : 227; }

std::string version_text(const LasHeader& h) {
  return std::to_string(h.version_major) + "." + std::to_string(h.version_minor);
}

const char* kDecompress =
    "decompress it first, e.g. `laszip -i in.laz -o out.las` (LAStools) or `pdal translate in.laz out.las` "
    "(cdtgpu reads uncompressed LAS only: Debian has no LASzip library)";

}  // namespace

int las_record_size(int point_format) {
  static constexpr int kSizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return point_format >= 0 && point_format <= 10 ? kSizes[point_format] : 0;
}

LasHeader parse_las_header(std::string_view bytes, const std::string& name) {
  auto fail = [&](const std::string& what) { throw InputError(name, 0, what); };
  if (bytes.size() < 4 || bytes.substr(0, 4) != "LASF") fail("not a LAS file (it does not start with \"LASF\")");
  LasHeader h;
  if (bytes.size() < 227)
    fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than a LAS header (227 bytes)");
  const char* b = bytes.data();
  h.version_major = uint8_t(b[24]);
  h.version_minor = uint8_t(b[25]);
  if (h.version_major != 1 || h.version_minor > 4)
    fail("LAS version " + version_text(h) + " is not supported (header bytes 24-25; cdtgpu reads 1.0 to 1.4)");
  h.global_encoding = get<uint16_t>(b + 6);
  h.header_size = get<uint16_t>(b + 94);
  h.point_offset = get<uint32_t>(b + 96);
  h.vlr_count = get<uint32_t>(b + 100);
  const uint8_t format = uint8_t(b[104]);
  h.record_length = get<uint16_t>(b + 105);
  const uint32_t legacy_count = get<uint32_t>(b + 107);
  for (int a = 0; a < 3; ++a) {
    h.scale[a] = get<double>(b + 131 + 8 * a);
    h.offset[a] = get<double>(b + 155 + 8 * a);
  }
  if (h.header_size < min_header_size(h.version_minor))
    fail("header size " + std::to_string(h.header_size) + " is less than LAS " + version_text(h) + "'s " +
         std::to_string(min_header_size(h.version_minor)) + " bytes");
  if (h.header_size > bytes.size())
    fail("truncated: the header size is " + std::to_string(h.header_size) + " bytes, the file has " +
         std::to_string(bytes.size()));
  // LASzip marks compressed point data by setting bit 7 (and some writers bit 6) of the format byte.
  if (format & 0xC0)
    fail("the point data are LAZ-compressed (point data format byte " + std::to_string(format) + "): " + kDecompress);
  if (format > 10) fail("point data record format " + std::to_string(format) + " is unknown (LAS 1.4 has 0 to 10)");
  h.point_format = format;
  if (h.record_length < las_record_size(format))
    fail("point data record length " + std::to_string(h.record_length) + " is shorter than format " +
         std::to_string(format) + "'s " + std::to_string(las_record_size(format)) + " bytes");
  uint64_t count = legacy_count;
  if (h.version_minor >= 4) {
    h.evlr_offset = get<uint64_t>(b + 235);
    h.evlr_count = get<uint32_t>(b + 243);
    const uint64_t count64 = get<uint64_t>(b + 247);
    // LAS 1.4 writers leave the legacy count 0 for formats 6-10 and beyond 2^32 points; where both are set
    // they must agree.
    if (count64 != 0 && legacy_count != 0 && count64 != legacy_count)
      fail("the point counts disagree: legacy number of point records " + std::to_string(legacy_count) +
           ", number of point records " + std::to_string(count64));
    if (count64 != 0) count = count64;
  }
  h.point_count = count;
  const char* axis = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(h.scale[a]) || h.scale[a] == 0)
      fail(std::string(1, axis[a]) + " scale factor " + number_text(h.scale[a]) + " is not a finite non-zero number");
    if (!std::isfinite(h.offset[a]))
      fail(std::string(1, axis[a]) + " offset " + number_text(h.offset[a]) + " is not a finite number");
  }
  if (h.point_offset < h.header_size)
    fail("offset to point data " + std::to_string(h.point_offset) + " lies inside the header (" +
         std::to_string(h.header_size) + " bytes)");
  const uint64_t room = h.point_offset <= bytes.size() ? (bytes.size() - h.point_offset) / h.record_length : 0;
  if (h.point_offset > bytes.size() || count > room)
    fail("truncated: the header gives " + std::to_string(count) + " points of " +
         std::to_string(h.record_length) + " bytes from byte " + std::to_string(h.point_offset) +
         ", the file has " + std::to_string(bytes.size()) + " bytes (room for " + std::to_string(room) + ")");
  return h;
}

namespace {

// A variable length record's payload.
struct Vlr {
  std::string user;  // user ID without its NUL padding
  uint16_t id = 0;
  std::string_view data;
};

std::string fixed_text(const char* p, size_t n) {
  std::string s(p, n);
  s.resize(std::strlen(s.c_str()));
  return s;
}

// The VLRs between the header and the points, and LAS 1.4's EVLRs after them.
std::vector<Vlr> records(std::string_view bytes, const LasHeader& h, const std::string& name) {
  std::vector<Vlr> out;
  uint64_t at = h.header_size;
  for (uint32_t k = 0; k < h.vlr_count; ++k) {
    if (at + 54 > h.point_offset)
      throw InputError(name, 0,
                       "VLR " + std::to_string(k + 1) + " of " + std::to_string(h.vlr_count) + " (at byte " +
                           std::to_string(at) + ") runs into the point data (from byte " +
                           std::to_string(h.point_offset) + ")");
    const char* p = bytes.data() + at;
    const uint64_t length = get<uint16_t>(p + 20);
    if (at + 54 + length > h.point_offset)
      throw InputError(name, 0,
                       "VLR " + std::to_string(k + 1) + " (" + std::to_string(length) + " bytes at byte " +
                           std::to_string(at + 54) + ") runs into the point data (from byte " +
                           std::to_string(h.point_offset) + ")");
    out.push_back({fixed_text(p + 2, 16), get<uint16_t>(p + 18), bytes.substr(at + 54, length)});
    at += 54 + length;
  }
  at = h.evlr_offset;
  for (uint32_t k = 0; k < h.evlr_count; ++k) {
    const uint64_t points_end = h.point_offset + h.point_count * h.record_length;  // checked against the size
    if (at < points_end)
      throw InputError(name, 0,
                       "extended VLR " + std::to_string(k + 1) + " of " + std::to_string(h.evlr_count) +
                           " would start at byte " + std::to_string(at) + ", before the end of the point data (byte " +
                           std::to_string(points_end) + ")");
    if (at > bytes.size() || bytes.size() - at < 60)
      throw InputError(name, 0,
                       "truncated: extended VLR " + std::to_string(k + 1) + " of " + std::to_string(h.evlr_count) +
                           " would start at byte " + std::to_string(at) + ", the file has " +
                           std::to_string(bytes.size()) + " bytes");
    const char* p = bytes.data() + at;
    const uint64_t length = get<uint64_t>(p + 20);
    if (length > bytes.size() - at - 60)
      throw InputError(name, 0,
                       "truncated: extended VLR " + std::to_string(k + 1) + " gives " + std::to_string(length) +
                           " bytes from byte " + std::to_string(at + 60) + ", the file has " +
                           std::to_string(bytes.size()));
    out.push_back({fixed_text(p + 2, 16), get<uint16_t>(p + 18), bytes.substr(at + 60, length)});
    at += 60 + length;
  }
  return out;
}

// The EPSG code in a GeoKeyDirectory (GeoTIFF 1.0 section 2.4): ProjectedCSTypeGeoKey (3072), else
// GeographicTypeGeoKey (2048); 0 when neither is there. `geographic` says which one.
int geokeys_epsg(std::string_view data, bool& geographic, const std::string& name) {
  const size_t shorts = data.size() / 2;
  auto at = [&](size_t i) { return get<uint16_t>(data.data() + 2 * i); };
  if (shorts < 4 || 4 + size_t(at(3)) * 4 > shorts)
    throw InputError(name, 0,
                     "the GeoKeyDirectory VLR (34735) is truncated: " + std::to_string(data.size()) + " bytes" +
                         (shorts >= 4 ? " for " + std::to_string(at(3)) + " keys" : std::string()));
  int projected = 0, geographic_code = 0;
  for (size_t k = 0; k < at(3); ++k) {
    const size_t e = 4 + 4 * k;
    if (at(e + 1) != 0) continue;  // a value stored elsewhere: not a code
    if (at(e) == 3072) projected = at(e + 3);
    if (at(e) == 2048) geographic_code = at(e + 3);
  }
  geographic = projected == 0 && geographic_code != 0;
  return projected ? projected : geographic_code;
}

// The file's CRS as a .prj's WKT: the WKT VLR's text, or the WKT of the GeoKeys' EPSG code; empty when the file
// names none, or a projected code cdtgpu does not know (coordinates kept as read, logged).
std::string las_crs_wkt(const std::vector<Vlr>& vlrs, const std::string& name) {
  for (const Vlr& v : vlrs)
    if (v.user == "LASF_Projection" && v.id == 2112) {
      std::string wkt = fixed_text(v.data.data(), v.data.size());
      while (!wkt.empty() && std::isspace(static_cast<unsigned char>(wkt.back()))) wkt.pop_back();
      if (!wkt.empty()) return wkt;
    }
  for (const Vlr& v : vlrs)
    if (v.user == "LASF_Projection" && v.id == 34735) {
      bool geographic = false;
      const int code = geokeys_epsg(v.data, geographic, name);
      if (code == 0) return {};
      std::string wkt = epsg_wkt(code);
      if (!wkt.empty()) return wkt;
      if (geographic)
        throw InputError(name, 0,
                         "its GeoKeys give the geographic CRS EPSG:" + std::to_string(code) +
                             ", a datum cdtgpu does not project (known: 4326 WGS 84, 4283 GDA94, 7844 GDA2020)");
      spdlog::warn("{}: its GeoKeys give EPSG:{}{}, which cdtgpu does not know: coordinates kept as read", name,
                   code, code == 32767 ? " (user-defined)" : "");
      return {};
    }
  return {};
}

// What the filters make of one record.
enum class Verdict : uint8_t { keep, withheld, other_return, other_class };

struct RecordFields {
  int cls;
  bool withheld;
  int ret, returns;
};

RecordFields fields(const char* p, int format) {
  const uint8_t b14 = uint8_t(p[14]), b15 = uint8_t(p[15]);
  if (format >= 6) return {uint8_t(p[16]), (b15 & 0x04) != 0, b14 & 15, b14 >> 4};
  return {b15 & 31, (b15 & 0x80) != 0, b14 & 7, (b14 >> 3) & 7};
}

Verdict judge(const RecordFields& f, const LasFilter& filter) {
  if (f.withheld && !filter.keep_withheld) return Verdict::withheld;
  if (filter.returns == LasFilter::Returns::first && f.ret > 1) return Verdict::other_return;
  if (filter.returns == LasFilter::Returns::last && f.ret < f.returns) return Verdict::other_return;
  if (!filter.classes.test(size_t(f.cls))) return Verdict::other_class;
  return Verdict::keep;
}

struct RangeCounts {
  std::array<uint64_t, 256> kept{}, skipped{};
  uint64_t withheld = 0, other_returns = 0, other_classes = 0, total_kept = 0;
};

}  // namespace

std::string las_nothing_kept(const PointClassCounts& counts) {
  uint64_t n = 0;  // every point is kept or skipped under its class
  std::string classes;
  for (const auto& [cls, count] : counts.by_class) {
    n += count.kept + count.skipped;
    if (count.skipped)
      classes += (classes.empty() ? "" : ", ") + std::to_string(cls) + " (" + std::to_string(count.skipped) + ")";
  }
  return n == 0 ? std::string("no geometry (the header gives 0 points)")
                : "no point passes the filters (" + std::to_string(n) + " points; by class: " + classes +
                      "; withheld: " + std::to_string(counts.withheld) +
                      "; other returns: " + std::to_string(counts.other_returns) + ")";
}

void read_las(const std::string& path, const LasFilter& filter, InputSet& in, const ReadShare* share) {
  if (!files::is_file(path)) throw InputError(path, 0, "no such file");
  const files::Open file(files::open(path));
  if (!file) throw InputError(path, 0, "cannot read: " + std::string(std::strerror(errno)));
  const std::string_view bytes = file->bytes();
  const LasHeader h = parse_las_header(bytes, path);
  const std::string crs = las_crs_wkt(records(bytes, h, path), path);
  const bool geographic = crs_wkt_is_geographic(crs);

  in.sources.push_back(path);
  const char* points = bytes.data() + h.point_offset;
  const uint64_t n = h.point_count;
  // With a share (io/read_share.hpp): its point records only.
  const auto [share_begin, share_end] = share ? share->range(n) : std::pair<uint64_t, uint64_t>(0, n);
  const uint64_t per_range = std::max<uint64_t>(
      1 << 16, (share_end - share_begin) / (4 * std::max(1u, std::thread::hardware_concurrency())) + 1);
  std::vector<Chunk> ranges;
  for (uint64_t first = share_begin; first < share_end; first += per_range)
    ranges.push_back({first, std::min(share_end, first + per_range), 0});

  // Pass 1: what each range keeps.
  std::vector<RangeCounts> counts(ranges.size());
  tbb::parallel_for(size_t(0), ranges.size(), [&](size_t k) {
    RangeCounts& c = counts[k];
    for (uint64_t i = ranges[k].begin; i < ranges[k].end; ++i) {
      const RecordFields f = fields(points + i * h.record_length, h.point_format);
      switch (judge(f, filter)) {
        case Verdict::keep: ++c.kept[size_t(f.cls)]; continue;
        case Verdict::withheld: ++c.withheld; break;
        case Verdict::other_return: ++c.other_returns; break;
        case Verdict::other_class: ++c.other_classes; break;
      }
      ++c.skipped[size_t(f.cls)];
    }
    for (uint64_t v : c.kept) c.total_kept += v;
  });
  std::vector<size_t> at(ranges.size() + 1, in.points.size());
  RangeCounts total;
  for (size_t k = 0; k < ranges.size(); ++k) {
    at[k + 1] = at[k] + counts[k].total_kept;
    total.withheld += counts[k].withheld;
    total.other_returns += counts[k].other_returns;
    total.other_classes += counts[k].other_classes;
    for (int cls = 0; cls < 256; ++cls) {
      total.kept[cls] += counts[k].kept[cls];
      total.skipped[cls] += counts[k].skipped[cls];
    }
  }
  PointClassCounts mine;  // this input's, for the message when nothing passes
  mine.any = true;
  mine.withheld = total.withheld;
  mine.other_returns = total.other_returns;
  mine.other_classes = total.other_classes;
  for (int cls = 0; cls < 256; ++cls)
    if (total.kept[cls] + total.skipped[cls]) mine.by_class[cls] = {total.kept[cls], total.skipped[cls]};
  in.point_classes.add(mine);
  if (at.back() == at.front() && !share) throw InputError(path, 0, las_nothing_kept(mine));

  // Pass 2: the kept points, in file order, each range into its own slice.
  resize_unwritten(in.points, at.back());  // written on all cores, the earlier inputs kept
  std::vector<Bounds> extents(ranges.size());
  parse_chunks(ranges, [&](size_t k, const Chunk& r) {
    Point3* out = in.points.data() + at[k];
    Bounds& e = extents[k];
    for (uint64_t i = r.begin; i < r.end; ++i) {
      const char* p = points + i * h.record_length;
      if (judge(fields(p, h.point_format), filter) != Verdict::keep) continue;
      const Point3 q{double(get<int32_t>(p)) * h.scale[0] + h.offset[0],
                     double(get<int32_t>(p + 4)) * h.scale[1] + h.offset[1],
                     double(get<int32_t>(p + 8)) * h.scale[2] + h.offset[2]};
      if (!(std::abs(q.x) <= kMaxCoordinate && std::abs(q.y) <= kMaxCoordinate && std::isfinite(q.z)))
        throw InputError(path, i + 1,
                         "point record " + std::to_string(i + 1) + ": X*scale+offset gives (" + number_text(q.x) +
                             " " + number_text(q.y) + " " + number_text(q.z) +
                             "), not finite or beyond ±1e15: check the header's scale factors and offsets");
      e.add(q);
      *out++ = q;
    }
  });
  Bounds all;
  for (const Bounds& e : extents) all.add(e);
  if (at.back() > at.front()) in.point_extents.push_back({at.front(), at.back(), all});
  if (geographic) {
    if (!(all.min_x >= -180 && all.max_x <= 180 && all.min_y >= -90 && all.max_y <= 90))
      throw InputError(path, 0,
                       "its CRS is geographic (longitude/latitude) but the points span x " + number_text(all.min_x) +
                           " to " + number_text(all.max_x) + ", y " + number_text(all.min_y) + " to " +
                           number_text(all.max_y));
  }
  if (in.source_crs_wkt.empty()) in.source_crs_wkt = crs;
}

}  // namespace cdtgpu
