// LAS 1.0-1.4 point clouds (ASPRS LAS specification 1.4 R15): the public header, point data record formats
// 0-10, and the per-input filters (cdtgpu triangulate ground.las:class=2,returns=last).
//
//   LasFilter f;  f.classes.reset();  f.classes.set(2);         // ground only
//   InputSet in;  read_las("tile.las", f, in);                   // every kept point a loose vertex
//   LasHeader h = parse_las_header(bytes, "tile.las");           // the header alone (tests, tools)
//
// Coordinates are X * scale + offset computed in double (one rounding for the product, one for the sum; the
// build forbids fused multiply-add), which is what PDAL, LAStools and laspy compute.
#pragma once
#include <bitset>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/model.hpp"

namespace cdtgpu {

struct LasFilter {
  std::bitset<256> classes = std::bitset<256>().set();  // class=2,8,9 (default: every class)
  bool keep_withheld = false;                           // withheld=keep (default: withheld points skipped)
  // first: return number 1; last: return number = number of returns. Points whose return fields are 0 (some
  // writers leave them unset) count as single returns, both first and last.
  enum class Returns : uint8_t { all, first, last } returns = Returns::all;
};

struct LasHeader {
  int version_major = 0, version_minor = 0;
  uint16_t global_encoding = 0;
  uint16_t header_size = 0;
  uint32_t point_offset = 0;  // offset to point data
  uint32_t vlr_count = 0;
  int point_format = 0;       // 0-10
  uint16_t record_length = 0;  // bytes per point record; more than the format's own is extra bytes
  uint64_t point_count = 0;    // the 64-bit count of LAS 1.4 where given, else the legacy 32-bit one
  double scale[3] = {}, offset[3] = {};
  uint64_t evlr_offset = 0;  // LAS 1.4: extended VLRs after the points
  uint32_t evlr_count = 0;
};

// The bytes of a point record of each format 0-10 without extra bytes.
int las_record_size(int point_format);

// Parses and checks the public header against the file's size (bytes: the whole file). Throws InputError
// naming the file and the header field for a missing signature, an unsupported version or point format, a
// compressed (LAZ) file, a record length shorter than its format, scales or offsets that are 0 or not finite,
// counts that disagree with each other or with the file size.
LasHeader parse_las_header(std::string_view bytes, const std::string& name);

// Reads the points that pass the filter as loose vertices (memory-mapped, decoded on all cores), the CRS from
// the OGC WKT VLR (record 2112) or the GeoTIFF GeoKeyDirectory VLR (34735) into in.source_crs_wkt when none was
// recorded yet, and the counts per class into in.point_classes.
// With a share (io/read_share.hpp): its point records only, and no check that some point passed (the caller's,
// once the shares are joined: las_nothing_kept).
struct ReadShare;
void read_las(const std::string& path, const LasFilter& filter, InputSet& in, const ReadShare* share = nullptr);

// Why an input of these counts (a LAS file's points, by class) gave no point.
std::string las_nothing_kept(const PointClassCounts& counts);

}  // namespace cdtgpu
