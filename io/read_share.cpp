#include "io/read_share.hpp"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>
#include <type_traits>

#include "core/touched.hpp"
#include "core/uninit.hpp"
#include "io/text_source.hpp"

namespace cdtgpu {

namespace {

// A piece's lines (without their points) and counts as bytes; its points and its lines' points go separately, each
// as one array.
class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof v);
  }
  void put_bytes(const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    bytes_.insert(bytes_.end(), c, c + n);
  }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

class Reader {
 public:
  Reader(const char* p, const char* end) : p_(p), end_(end) {}
  template <typename T>
  T get() {
    T v;
    get_bytes(&v, sizeof v);
    return v;
  }
  void get_bytes(void* out, size_t n) {
    if (size_t(end_ - p_) < n) throw std::runtime_error("read share: a share's bytes end early");
    std::memcpy(out, p_, n);
    p_ += n;
  }

 private:
  const char* p_;
  const char* end_;
};

std::vector<char> pack(const InputSet& piece) {
  Writer w;
  w.put(uint64_t(piece.lines.size()));
  for (const Polyline& line : piece.lines) {
    w.put(uint64_t(line.points.size()));
    w.put(uint8_t(line.closed));
    w.put(line.source);
    w.put(line.record);
  }
  const Repairs& r = piece.repairs;
  for (uint64_t v : {r.repeated_vertices, r.rings_closed, r.degenerate_lines, r.null_shapes, r.nodata_cells}) w.put(v);
  const PointClassCounts& pc = piece.point_classes;
  w.put(uint8_t(pc.any));
  for (uint64_t v : {pc.withheld, pc.other_returns, pc.other_classes, uint64_t(pc.by_class.size())}) w.put(v);
  for (const auto& [cls, count] : pc.by_class) {
    w.put(int32_t(cls));
    w.put(count.kept);
    w.put(count.skipped);
  }
  w.put(uint64_t(piece.source_crs_wkt.size()));
  w.put_bytes(piece.source_crs_wkt.data(), piece.source_crs_wkt.size());
  return w.bytes();
}

InputSet unpack(Reader& r) {
  InputSet piece;
  piece.lines.resize(r.get<uint64_t>());
  for (Polyline& line : piece.lines) {
    line.points.resize(r.get<uint64_t>());
    line.closed = r.get<uint8_t>() != 0;
    line.source = r.get<uint32_t>();
    line.record = r.get<uint64_t>();
  }
  Repairs& rep = piece.repairs;
  for (uint64_t* v : {&rep.repeated_vertices, &rep.rings_closed, &rep.degenerate_lines, &rep.null_shapes,
                      &rep.nodata_cells})
    *v = r.get<uint64_t>();
  PointClassCounts& pc = piece.point_classes;
  pc.any = r.get<uint8_t>() != 0;
  pc.withheld = r.get<uint64_t>();
  pc.other_returns = r.get<uint64_t>();
  pc.other_classes = r.get<uint64_t>();
  for (uint64_t k = r.get<uint64_t>(); k > 0; --k) {
    const int cls = r.get<int32_t>();
    PointClassCounts::Count& c = pc.by_class[cls];
    c.kept = r.get<uint64_t>();
    c.skipped = r.get<uint64_t>();
  }
  piece.source_crs_wkt.resize(r.get<uint64_t>());
  r.get_bytes(piece.source_crs_wkt.data(), piece.source_crs_wkt.size());
  return piece;
}

// The first line start at or after byte `at` (a line starts at 0 or after a '\n').
size_t line_start(std::string_view text, size_t at) {
  if (at == 0 || at >= text.size()) return std::min(at, text.size());
  const size_t nl = text.find('\n', at - 1);
  return nl == std::string_view::npos ? text.size() : nl + 1;
}

}  // namespace

std::pair<size_t, size_t> share_lines(std::string_view text, const ReadShare& share) {
  const auto [first, last] = share.range(text.size());
  return {line_start(text, first), line_start(text, last)};
}

PointClassCounts join_shares(InputSet& piece, const ReadShare& share, InputSet& in) {
  // Points: every share's, in share order, at the end of in.points.
  const auto t0 = std::chrono::steady_clock::now();
  auto ms = [&] { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count(); };
  const std::vector<uint64_t> point_bytes = share.all_sizes(piece.points.size() * sizeof(Point3));
  const double sizes_ms = ms();
  uint64_t total = 0;
  for (uint64_t b : point_bytes) total += b;
  const bool first = share.index == 0;
  const size_t at = in.points.size();
  // Touched first on all cores: MPI's receive faulting fresh pages in ran at ~1.5 GB/s, touched ones ~4.
  if (first) resize_touched(in.points, at + total / sizeof(Point3));
  share.gather_bytes(reinterpret_cast<const char*>(piece.points.data()),
                     first ? reinterpret_cast<char*>(in.points.data() + at) : nullptr, point_bytes);
  const double points_ms = ms();
  free_storage(piece.points);

  const std::vector<char> mine = pack(piece);  // before the lines' points go below
  // The lines' points, one array of every share's in share order (each line's in turn), exchanged the same way.
  // Packed with the lines, they were ~1.3 s of copies on one core for 25M points at 100M on the 2 x H200 host.
  std::vector<uint64_t> line_at(piece.lines.size() + 1, 0);
  for (size_t i = 0; i < piece.lines.size(); ++i) line_at[i + 1] = line_at[i] + piece.lines[i].points.size();
  Points mine_line_points;
  resize_unwritten(mine_line_points, line_at.back());
  tbb::parallel_for(size_t(0), piece.lines.size(), [&](size_t i) {
    Points& from = piece.lines[i].points;
    std::copy(from.begin(), from.end(), mine_line_points.begin() + std::ptrdiff_t(line_at[i]));
    free_storage(from);
  });
  const std::vector<uint64_t> line_bytes = share.all_sizes(mine_line_points.size() * sizeof(Point3));
  uint64_t line_total = 0;
  for (uint64_t b : line_bytes) line_total += b;
  Points line_points;
  if (first) resize_touched(line_points, line_total / sizeof(Point3));
  share.gather_bytes(reinterpret_cast<const char*>(mine_line_points.data()),
                     first ? reinterpret_cast<char*>(line_points.data()) : nullptr, line_bytes);
  free_storage(mine_line_points);

  // The lines and counts, packed.
  const std::vector<uint64_t> sizes = share.all_sizes(mine.size());
  uint64_t all_size = 0;
  for (uint64_t s : sizes) all_size += s;
  std::vector<char> all(first ? all_size : 0);
  share.gather_bytes(mine.data(), first ? all.data() : nullptr, sizes);
  if (!first) return {};
  std::vector<InputSet> pieces;
  std::vector<Polyline*> lines;
  const char* p = all.data();
  for (uint64_t s : sizes) {
    Reader r(p, p + s);
    pieces.push_back(unpack(r));
    for (Polyline& line : pieces.back().lines) lines.push_back(&line);
    p += s;
  }
  std::vector<uint64_t> from(lines.size() + 1, 0);
  for (size_t i = 0; i < lines.size(); ++i) from[i + 1] = from[i] + lines[i]->points.size();
  if (from.back() != line_points.size()) throw std::runtime_error("read share: the lines' points do not add up");
  tbb::parallel_for(size_t(0), lines.size(), [&](size_t i) {
    std::copy(line_points.begin() + std::ptrdiff_t(from[i]), line_points.begin() + std::ptrdiff_t(from[i + 1]),
              lines[i]->points.begin());
  });
  free_storage(line_points);
  PointClassCounts input_classes;
  for (const InputSet& part : pieces) {
    if (in.source_crs_wkt.empty()) in.source_crs_wkt = part.source_crs_wkt;
    input_classes.add(part.point_classes);
  }
  in.point_classes.add(input_classes);
  append_parts(in, pieces);  // lines and repairs
  // The first figure is mostly the wait for the slowest share's reading.
  spdlog::debug("read: shares joined: sizes known at {:.0f} ms, points ({:.0f} MB) at {:.0f} ms, lines at {:.0f} ms",
                sizes_ms, total / 1e6, points_ms, ms());
  return input_classes;
}

}  // namespace cdtgpu
