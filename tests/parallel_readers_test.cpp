// The text readers parse in chunks on all cores (io/text_source.hpp): inputs of several chunks must give the
// same points, lines, repairs and error lines as reading line by line would.
#include <gtest/gtest.h>
#include <shapefil.h>

#include <algorithm>
#include <cmath>

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/touched.hpp"
#include "io/readers.hpp"
#include "io/text_source.hpp"

using namespace cdtgpu;

namespace {

std::string num(double v) {
  char buf[32];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

// n points, one per line, with comments and blank lines between them; far over one chunk (256 KiB).
std::string xyz_text(int n, Points& expected) {
  std::string s = "x,y,z\n";
  for (int i = 0; i < n; ++i) {
    const Point3 p{500000 + i * 0.25, 6000000 + (i % 977) * 1.5, i * 0.001};
    expected.push_back(p);
    s += num(p.x) + "," + num(p.y) + "," + num(p.z) + (i % 7 == 0 ? "\r\n" : "\n");
    if (i % 1000 == 0) s += "# comment\n\n";
  }
  return s;
}

// Line number (1-based) of the first line of `s` that contains `needle`.
uint64_t line_of(const std::string& s, const std::string& needle) {
  const size_t at = s.find(needle);
  return 1 + uint64_t(std::count(s.begin(), s.begin() + std::ptrdiff_t(at), '\n'));
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

// Readers append to what earlier inputs read: growing a vector past its storage keeps its elements and zeroes
// only the new ones (a 24 MB vector, so the pages are touched on all cores).
TEST(ResizeTouched, KeepsTheElementsItHasAndZeroesTheNew) {
  Points v(1000, Point3{1, 2, 3});
  v.shrink_to_fit();
  resize_touched(v, 1000000);
  ASSERT_EQ(v.size(), 1000000u);
  EXPECT_EQ(std::count(v.begin(), v.begin() + 1000, Point3{1, 2, 3}), 1000);
  EXPECT_EQ(std::count(v.begin() + 1000, v.end(), Point3{0, 0, 0}), 999000);
  // Within its storage: a RawVector's own resize writes nothing, so the new elements are zeroed here, also
  // after garbage was left there (resize_unwritten, then a shrink).
  resize_unwritten(v, 2000000);
  std::fill(v.begin(), v.end(), Point3{7, 7, 7});
  v.resize(10);
  resize_touched(v, 1500000);
  EXPECT_EQ(std::count(v.begin(), v.begin() + 10, Point3{7, 7, 7}), 10);
  EXPECT_EQ(std::count(v.begin() + 10, v.end(), Point3{0, 0, 0}), 1499990);
  v.resize(10);
  resize_touched(v, 20);
  EXPECT_EQ(std::count(v.begin() + 10, v.end(), Point3{0, 0, 0}), 10);
}

// release_pages gives back exactly the whole pages inside its range, in pieces on all cores past 64 MB: they
// read as zeros again, the bytes of the pages it only partly covers keep their values.
TEST(ReleasePages, GivesBackTheWholePagesInsideItsRangeOnly) {
  RawVector<uint8_t> v;
  resize_unwritten(v, size_t(200) << 20);
  std::fill(v.begin(), v.end(), uint8_t(5));
  const size_t from = 1000, to = v.size() - 3000;  // neither on a page boundary (the storage is page-aligned)
  release_pages(v.data() + from, to - from);
  const size_t first_whole = (reinterpret_cast<uintptr_t>(v.data()) + from + 4095) / 4096 * 4096 -
                             reinterpret_cast<uintptr_t>(v.data());
  const size_t end_whole = (reinterpret_cast<uintptr_t>(v.data()) + to) / 4096 * 4096 - reinterpret_cast<uintptr_t>(v.data());
  ASSERT_LT(first_whole, end_whole);
  EXPECT_EQ(std::count(v.begin(), v.begin() + first_whole, uint8_t(5)), ptrdiff_t(first_whole));
  EXPECT_EQ(std::count(v.begin() + first_whole, v.begin() + end_whole, uint8_t(0)), ptrdiff_t(end_whole - first_whole));
  EXPECT_EQ(std::count(v.begin() + end_whole, v.end(), uint8_t(5)), ptrdiff_t(v.size() - end_whole));
  free_storage_on_all_cores(v);
  EXPECT_EQ(v.capacity(), 0u);
}

TEST(TextSource, SplitLinesEndsEveryChunkAtALineEndAndNumbersLines) {
  const std::string text = "a\nbb\nccc\ndddd\ne";
  const std::vector<Chunk> chunks = split_lines(text, 3);
  ASSERT_FALSE(chunks.empty());
  EXPECT_EQ(chunks.front().begin, 0u);
  EXPECT_EQ(chunks.back().end, text.size());
  uint64_t line = 1;
  for (size_t k = 0; k < chunks.size(); ++k) {
    if (k > 0) {
      EXPECT_EQ(chunks[k].begin, chunks[k - 1].end);
    }
    if (chunks[k].end < text.size()) {
      EXPECT_EQ(text[chunks[k].end - 1], '\n');
    }
    EXPECT_EQ(chunks[k].first_line, line);
    line += uint64_t(std::count(text.begin() + long(chunks[k].begin), text.begin() + long(chunks[k].end), '\n'));
  }
}

TEST(TextSource, MapsAFileAndDropsTheByteOrderMark) {
  const auto path = std::filesystem::temp_directory_path() / "cdtgpu_text_source.xyz";
  std::ofstream(path, std::ios::binary) << "\xEF\xBB\xBF" << "1 2 3\n";
  EXPECT_EQ(TextSource::open(path.string()).text(), "1 2 3\n");
  std::filesystem::remove(path);
}

TEST(ParallelReaders, XyzOfManyChunksGivesEveryPointInOrder) {
  Points expected;
  const std::string text = xyz_text(60000, expected);
  ASSERT_GT(text.size(), 4u * chunk_bytes(0));
  InputSet in;
  read_xyz_text(text, "big.xyz", in);
  EXPECT_EQ(in.points, expected);
}

TEST(ParallelReaders, XyzReportsTheFirstBadLineOfTheFile) {
  Points expected;
  std::string text = xyz_text(60000, expected);
  // Two errors in different chunks: the earlier one is reported, with its own line number.
  const std::string late = num(expected[55000].x) + ",";
  const std::string early = num(expected[31000].x) + ",";
  text.replace(text.find(late), late.size(), "oops,");
  const uint64_t early_line = line_of(text, early);
  text.replace(text.find(early), early.size(), num(expected[31000].x) + ",nan_or_worse,");
  EXPECT_EQ(error_of([&] {
              InputSet in;
              read_xyz_text(text, "big.xyz", in);
            }),
            "big.xyz:" + std::to_string(early_line) + ": column 2 is not a number: 'nan_or_worse'");
}

TEST(ParallelReaders, WktGeometriesSpanningChunkEndsAreReadWhole) {
  // Every LINESTRING spans three lines, so some cross chunk ends; degenerate ones become points in order.
  std::string text;
  Points points;
  size_t lines = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = 500000 + i, y = 6000000 + (i % 13);
    if (i % 5 == 0) {
      text += "LINESTRING Z (" + num(x) + " " + num(y) + " 1,\n" + num(x) + " " + num(y) + " 1)\n";
      points.push_back({x, y, 1});  // one distinct vertex: kept as a point
    } else {
      text += "LINESTRING Z (" + num(x) + " " + num(y) + " 1,\n  " + num(x + 0.5) + " " + num(y) + " 2,\n  " +
              num(x + 0.5) + " " + num(y + 0.5) + " 3)\n";
      ++lines;
    }
    if (i % 3 == 0) text += "\n";
  }
  ASSERT_GT(text.size(), 4u * chunk_bytes(0));
  InputSet in;
  read_wkt_text(text, "big.wkt", in);
  EXPECT_EQ(in.points, points);
  ASSERT_EQ(in.lines.size(), lines);
  EXPECT_EQ(in.repairs.degenerate_lines, 4000u);
  for (const Polyline& l : in.lines) ASSERT_EQ(l.points.size(), 3u);
  // Records are the geometries' first lines: the 7th geometry (i = 6) starts on line ...
  EXPECT_EQ(in.lines[4].record, line_of(text, "LINESTRING Z (500006 "));
  EXPECT_EQ(in.lines.back().points.back().x, 500000 + 19999 + 0.5);
}

TEST(ParallelReaders, WktReportsTheFirstBadGeometryOfTheFile) {
  std::string text;
  for (int i = 0; i < 40000; ++i)
    text += "POINT (" + num(500000 + i) + " 6000000)\n" + (i % 2 ? "LINESTRING (0 0,\n 1 1)\n" : "");
  const std::string early = "POINT (530000 ", late = "POINT (535000 ";
  text.replace(text.find(late), late.size(), "POINT (535000 x ");
  text.replace(text.find(early), early.size(), "PIONT (530000 ");
  EXPECT_EQ(error_of([&] {
              InputSet in;
              read_wkt_text(text, "big.wkt", in);
            }),
            "big.wkt:" + std::to_string(line_of(text, "PIONT")) + ": unknown geometry type 'PIONT'");
  // An unclosed '(' at the very end names the geometry's line.
  std::string open = text.substr(0, text.find("PIONT")) + "LINESTRING (1 2, 3 4\n";
  EXPECT_NE(error_of([&] {
              InputSet in;
              read_wkt_text(open, "open.wkt", in);
            }).find("open.wkt:" + std::to_string(line_of(open, "LINESTRING (1 2, 3 4"))),
            std::string::npos);
}

// Shapefiles are read in ranges of records on all cores (io/read_shapefile.cpp): more records than one range
// must come back in order, and a bad record in a later range is the one named.
TEST(ParallelReaders, ShapefileOfManyRangesGivesEveryPointInOrderAndNamesTheBadRecord) {
  const auto dir = std::filesystem::temp_directory_path() / "cdtgpu_parallel_shp";
  std::filesystem::create_directories(dir);
  const std::string base = (dir / "pts").string();
  auto write = [&]() {
    SHPHandle shp = SHPCreate(base.c_str(), SHPT_POINTZ);
    DBFHandle dbf = DBFCreate(base.c_str());
    DBFAddField(dbf, "ID", FTInteger, 10, 0);
    for (int i = 0; i < 30000; ++i) {
      double x = 500000 + i * 0.5, y = 6000000 + (i % 101), z = i * 0.01;
      SHPObject* o = SHPCreateSimpleObject(SHPT_POINTZ, 1, &x, &y, &z);
      SHPWriteObject(shp, -1, o);
      SHPDestroyObject(o);
      DBFWriteIntegerAttribute(dbf, i, 0, i);
    }
    SHPClose(shp);
    DBFClose(dbf);
  };
  write();
  InputSet in;
  read_shapefile(base + ".shp", {}, in);
  ASSERT_EQ(in.points.size(), 30000u);
  for (int i = 0; i < 30000; ++i) ASSERT_EQ(in.points[size_t(i)], (Point3{500000 + i * 0.5, 6000000.0 + (i % 101), i * 0.01})) << i;
  // Record 27001's x (12 bytes into the record; its offset from the .shx, big-endian 16-bit words) made far
  // larger than the header's box says.
  {
    std::ifstream shx(base + ".shx", std::ios::binary);
    unsigned char e[4];
    shx.seekg(100 + 27000 * 8);
    shx.read(reinterpret_cast<char*>(e), 4);
    const long offset = 2L * (long(e[0]) << 24 | long(e[1]) << 16 | long(e[2]) << 8 | long(e[3]));
    std::fstream f(base + ".shp", std::ios::binary | std::ios::in | std::ios::out);
    const double far = 1e300;
    f.seekp(offset + 12);
    f.write(reinterpret_cast<const char*>(&far), 8);
  }
  const std::string err = error_of([&] {
    InputSet bad;
    read_shapefile(base + ".shp", {}, bad);
  });
  EXPECT_NE(err.find("pts.shp:27001:"), std::string::npos) << err;
  std::filesystem::remove_all(dir);
}

// A file of few long records (contours of many vertices) is split by bytes, not by records: each of 12 lines of
// 20000 vertices comes back whole and in order (chunks of 4096 records read such a file on one core).
TEST(ParallelReaders, ShapefileOfFewLongLinesGivesEveryLineInOrder) {
  const auto dir = std::filesystem::temp_directory_path() / "cdtgpu_parallel_shp_lines";
  std::filesystem::create_directories(dir);
  const std::string base = (dir / "lines").string();
  SHPHandle shp = SHPCreate(base.c_str(), SHPT_ARCZ);
  DBFHandle dbf = DBFCreate(base.c_str());
  DBFAddField(dbf, "ID", FTInteger, 10, 0);
  constexpr int kLines = 12, kVertices = 20000;
  auto vertex = [](int l, int k) { return Point3{500000 + k * 0.25, 6000000 + l * 10 + (k % 7) * 0.125, l + k * 0.001}; };
  for (int l = 0; l < kLines; ++l) {
    std::vector<double> x, y, z;
    for (int k = 0; k < kVertices; ++k) {
      const Point3 p = vertex(l, k);
      x.push_back(p.x), y.push_back(p.y), z.push_back(p.z);
    }
    SHPObject* o = SHPCreateSimpleObject(SHPT_ARCZ, kVertices, x.data(), y.data(), z.data());
    SHPWriteObject(shp, -1, o);
    SHPDestroyObject(o);
    DBFWriteIntegerAttribute(dbf, l, 0, l);
  }
  SHPClose(shp);
  DBFClose(dbf);
  InputSet in;
  read_shapefile(base + ".shp", {}, in);
  ASSERT_EQ(in.lines.size(), size_t(kLines));
  for (int l = 0; l < kLines; ++l) {
    ASSERT_EQ(in.lines[l].record, uint64_t(l) + 1);
    ASSERT_EQ(in.lines[l].points.size(), size_t(kVertices)) << l;
    for (int k = 0; k < kVertices; ++k) ASSERT_EQ(in.lines[l].points[size_t(k)], vertex(l, k)) << l << " " << k;
  }
  std::filesystem::remove_all(dir);
}

namespace {

// A 300 x 400 grid (about 1 MB of text: several chunks), NODATA here and there, one row a line unless
// `wrapped` (then rows are split over lines of 7 values, as some writers wrap them).
std::string asc_text(bool wrapped, bool centre) {
  std::string s = "ncols 300\nnrows 400\n";
  s += centre ? "xllcenter 500000.5\nyllcenter 6000000.5\n" : "xllcorner 500000\nyllcorner 6000000\n";
  s += "cellsize 2.5\nNODATA_value -9999\n";
  for (int r = 0; r < 400; ++r) {
    for (int c = 0; c < 300; ++c) {
      const bool nodata = (r * 300 + c) % 97 == 0;
      s += nodata ? std::string("-9999") : num(100 + r * 0.125 - c * 0.0625);
      s += (wrapped && c % 7 == 6) || c == 299 ? (r % 5 ? "\n" : "\r\n") : " ";
    }
  }
  return s;
}

// The sequential reader (std::istream), for comparison.
InputSet asc_sequential(const std::string& text) {
  InputSet in;
  std::istringstream s(text);
  read_ascii_grid(s, "dem.asc", in);
  return in;
}

}  // namespace

TEST(ParallelReaders, AsciiGridGivesTheSequentialReadersVertices) {
  for (const bool wrapped : {false, true})
    for (const bool centre : {false, true}) {
      const std::string text = asc_text(wrapped, centre);
      ASSERT_GT(text.size(), 3u * chunk_bytes(0));
      InputSet in;
      in.points.push_back({1, 2, 3});  // an earlier input's vertex stays
      read_ascii_grid_text(text, "dem.asc", in);
      const InputSet want = asc_sequential(text);
      ASSERT_EQ(in.points.size(), want.points.size() + 1);
      EXPECT_EQ(in.points[0], (Point3{1, 2, 3}));
      EXPECT_TRUE(std::equal(want.points.begin(), want.points.end(), in.points.begin() + 1));
      EXPECT_EQ(in.repairs.nodata_cells, want.repairs.nodata_cells);
      EXPECT_EQ(in.repairs.nodata_cells, 1238u);  // every 97th of 120000 cells
      EXPECT_EQ(in.sources, (std::vector<std::string>{"dem.asc"}));
    }
}

// Any fault in the data is reported as the sequential reader reports it: the first in the file.
TEST(ParallelReaders, AsciiGridReportsTheFirstFaultOfTheFile) {
  const std::string good = asc_text(false, false);
  auto both = [](const std::string& text) {
    const std::string seq = error_of([&] { asc_sequential(text); });
    const std::string par = error_of([&] {
      InputSet in;
      read_ascii_grid_text(text, "dem.asc", in);
    });
    EXPECT_EQ(par, seq);
    return par;
  };
  // A bad value in the last row, then also a short second row: the short row is first.
  std::string text = good;
  text.replace(text.rfind("\n149.875 "), 9, "\n149.875x ");
  EXPECT_EQ(both(text), "dem.asc:406: not a number: '149.875x'");
  text.erase(text.find("\n100.125 ") + 1, 8);
  EXPECT_EQ(both(text), "dem.asc:8: row 2 has 299 values, ncols is 300");
  // Values missing at the end, one too many, NaN without NODATA, a coordinate out of range.
  EXPECT_NE(both(good.substr(0, good.size() - 20)).find("row 400 has"), std::string::npos);
  EXPECT_NE(both(good + "7\n").find("more values than"), std::string::npos);
  std::string with_nan = good;
  with_nan.replace(with_nan.rfind("\n149.875 "), 9, "\nnan ");
  EXPECT_NE(both(with_nan).find("not a finite number"), std::string::npos);
  std::string far = good;
  far.replace(far.find("xllcorner 500000"), 16, "xllcorner 5e15");
  EXPECT_NE(both(far).find("beyond"), std::string::npos);
}
