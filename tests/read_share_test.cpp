// Inputs read in shares (io/read_share.hpp, the MPI ranks' reading): every share count gives every share the
// InputSet of one whole read (points in order, lines, repairs, LAS classes, CRS, sources, parts), and errors
// name the record a whole read names. The shares run on threads here, joined through an exchange of their
// own (cli/mpi.cpp gives MPI's; tests/mpi_test runs that one).
#include <gtest/gtest.h>
#include <shapefil.h>

#include <barrier>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "io/input_spec.hpp"
#include "io/read_share.hpp"
#include "io/readers.hpp"
#include "io/text_source.hpp"
#include "tests/las_writer.hpp"

namespace {

using namespace cdtgpu;

// Gathers among `count` threads, as MPI ranks do (cli/mpi.cpp): each posts its own and waits for all; the first
// copies every one; all wait again.
class ThreadExchange {
 public:
  explicit ThreadExchange(uint32_t count) : sync_(count), sizes_(count), data_(count) {
    for (uint32_t i = 0; i < count; ++i) {
      ReadShare& s = shares_.emplace_back();
      s.index = i;
      s.count = count;
      s.all_sizes = [this, i](uint64_t mine) {
        sizes_[i] = mine;
        sync_.arrive_and_wait();
        std::vector<uint64_t> all = sizes_;
        sync_.arrive_and_wait();
        return all;
      };
      s.gather_bytes = [this, i](const char* mine, char* all, const std::vector<uint64_t>& sizes) {
        data_[i] = mine;
        sync_.arrive_and_wait();
        for (size_t r = 0; all && r < sizes.size(); ++r) {
          if (sizes[r]) std::memcpy(all, data_[r], sizes[r]);
          all += sizes[r];
        }
        sync_.arrive_and_wait();
      };
    }
  }
  const ReadShare& share(uint32_t i) const { return shares_[i]; }

 private:
  std::barrier<> sync_;
  std::vector<uint64_t> sizes_;
  std::vector<const char*> data_;
  std::vector<ReadShare> shares_;
};

// Bit for bit: vertices read without z carry a NaN (missing_z).
bool same_points(const Points& a, const Points& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Point3)) == 0);
}

void expect_same(const InputSet& a, const InputSet& b, const std::string& what) {
  ASSERT_EQ(a.points.size(), b.points.size()) << what;
  ASSERT_TRUE(same_points(a.points, b.points)) << what;
  ASSERT_EQ(a.lines.size(), b.lines.size()) << what;
  for (size_t i = 0; i < a.lines.size(); ++i) {
    const Polyline &p = a.lines[i], &q = b.lines[i];
    ASSERT_TRUE(same_points(p.points, q.points)) << what << " line " << i;
    EXPECT_EQ(p.closed, q.closed) << what << " line " << i;
    EXPECT_EQ(p.source, q.source) << what << " line " << i;
    EXPECT_EQ(p.record, q.record) << what << " line " << i;
  }
  EXPECT_EQ(a.sources, b.sources) << what;
  EXPECT_EQ(a.source_crs_wkt, b.source_crs_wkt) << what;
  const Repairs &r = a.repairs, &s = b.repairs;
  EXPECT_EQ(r.repeated_vertices, s.repeated_vertices) << what;
  EXPECT_EQ(r.rings_closed, s.rings_closed) << what;
  EXPECT_EQ(r.degenerate_lines, s.degenerate_lines) << what;
  EXPECT_EQ(r.null_shapes, s.null_shapes) << what;
  EXPECT_EQ(a.point_classes.any, b.point_classes.any) << what;
  EXPECT_EQ(a.point_classes.withheld, b.point_classes.withheld) << what;
  EXPECT_EQ(a.point_classes.other_classes, b.point_classes.other_classes) << what;
  ASSERT_EQ(a.point_classes.by_class.size(), b.point_classes.by_class.size()) << what;
  for (const auto& [cls, c] : a.point_classes.by_class) {
    EXPECT_EQ(c.kept, b.point_classes.by_class.at(cls).kept) << what << " class " << cls;
    EXPECT_EQ(c.skipped, b.point_classes.by_class.at(cls).skipped) << what << " class " << cls;
  }
}

class ReadShareTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("cdtgpu_read_share_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }

  // Every share's InputSet of `args` (PATH[:options]) read by `count` threads.
  std::vector<InputSet> read_shared(const std::vector<std::string>& args, uint32_t count,
                                    std::vector<std::vector<InputPart>>* parts = nullptr) const {
    std::vector<InputSpec> specs;
    for (const std::string& a : args) specs.push_back(parse_input_spec(a));
    ThreadExchange exchange(count);
    std::vector<InputSet> ins(count);
    std::vector<std::vector<InputPart>> got(count);
    std::vector<std::exception_ptr> errors(count);
    std::vector<std::thread> threads;
    for (uint32_t i = 0; i < count; ++i)
      threads.emplace_back([&, i] {
        ReadOptions options;
        options.share = &exchange.share(i);
        try {
          got[i] = read_inputs(specs, options, ins[i]);
        } catch (...) {
          errors[i] = std::current_exception();
        }
      });
    for (std::thread& t : threads) t.join();
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
    if (parts) *parts = got;
    return ins;
  }
  InputSet read_whole(const std::vector<std::string>& args, std::vector<InputPart>* parts = nullptr) const {
    std::vector<InputSpec> specs;
    for (const std::string& a : args) specs.push_back(parse_input_spec(a));
    InputSet in;
    std::vector<InputPart> got = read_inputs(specs, ReadOptions{}, in);
    if (parts) *parts = got;
    return in;
  }

  std::filesystem::path dir_;
};

// XYZ text: comments and blank lines first, a header, CRLF and ';' lines; about 40 bytes a line.
std::string dem_text(int n) {
  std::string s = "# a DEM\n\n# exported\r\nX,Y,Z\r\n";
  for (int i = 0; i < n; ++i) {
    s += std::to_string(500000 + (i * 37) % 211) + "." + std::to_string(i % 10) + "," +
         std::to_string(6000000 + (i * 53) % 197) + ",";
    s += std::to_string(100 + i % 13) + (i % 7 == 0 ? "\r\n" : "\n");
    if (i % 50 == 0) s += "   # a comment\n\n";
  }
  return s;
}

void write_lines_shapefile(const std::string& base) {
  SHPHandle shp = SHPCreate(base.c_str(), SHPT_ARCZ);
  for (int i = 0; i < 40; ++i) {
    if (i % 9 == 4) {  // a NULL shape: counted in the repairs
      SHPObject* o = SHPCreateSimpleObject(SHPT_NULL, 0, nullptr, nullptr, nullptr);
      SHPWriteObject(shp, -1, o);
      SHPDestroyObject(o);
      continue;
    }
    // A repeated vertex in every third record: counted in the repairs.
    double x[4] = {500010.0 + i * 4, 500030.0 + i * 4, 500030.0 + i * 4, 500050.0 + i * 4};
    double y[4] = {6000010.0 + i, 6000090.0 - i, 6000090.0 - i, 6000150.0 + i};
    double z[4] = {10, 11, 11, 12};
    if (i % 3 != 0) x[2] += 1;
    SHPObject* o = SHPCreateSimpleObject(SHPT_ARCZ, 4, x, y, z);
    SHPWriteObject(shp, -1, o);
    SHPDestroyObject(o);
  }
  SHPClose(shp);
}

std::string las_of(int n) {
  test::LasFile f;
  f.minor = 4;
  f.format = 6;
  f.vlrs.push_back(test::geokeys_vlr(3072, 28356));  // MGA zone 56
  for (int i = 0; i < n; ++i)
    f.points.push_back({.X = 1000 + (i * 7919) % 20000, .Y = 1000 + (i * 104729) % 20000, .Z = 500 + i % 900,
                        .cls = uint8_t(i % 5 == 0 ? 1 : 2), .withheld = i % 97 == 3});
  return test::las_bytes(f);
}

TEST_F(ReadShareTest, EveryShareCountGivesTheWholeRead) {
  write("dem.csv", dem_text(3000));
  write_lines_shapefile(path("lines"));
  write("ground.las", las_of(5000));
  write("rings.wkt",
        "POLYGON ((500012 6000012, 500180 6000015, 500170 6000185, 500012 6000012))\n"
        "LINESTRING (499995 6000100, 500205 6000101, 500205 6000101, 500300 6000150)\n");
  write("more.xyz", "500001 6000001 5\n500002 6000003 6\n");
  const std::vector<std::string> args = {path("dem.csv"),  path("lines.shp:z=drape"), path("ground.las:class=2"),
                                         path("rings.wkt"), path("lines.shp:role=vertices"), path("more.xyz")};
  std::vector<InputPart> whole_parts;
  const InputSet whole = read_whole(args, &whole_parts);
  ASSERT_GT(whole.points.size(), 6000u);
  ASSERT_GT(whole.repairs.null_shapes, 0u);
  ASSERT_GT(whole.repairs.repeated_vertices, 0u);
  for (uint32_t count : {1u, 2u, 3u, 5u, 8u}) {
    std::vector<std::vector<InputPart>> parts;
    const std::vector<InputSet> ins = read_shared(args, count, &parts);
    // The first share holds the whole input; the others sent theirs and hold nothing.
    for (uint32_t i = 1; i < count; ++i) {
      EXPECT_TRUE(ins[i].points.empty()) << "share " << i << " of " << count;
      EXPECT_TRUE(ins[i].lines.empty()) << "share " << i << " of " << count;
    }
    const std::string what = "share 0 of " + std::to_string(count);
    expect_same(ins[0], whole, what);
    ASSERT_EQ(parts[0].size(), whole_parts.size());
    for (size_t k = 0; k < parts[0].size(); ++k) {
      EXPECT_EQ(parts[0][k].points_begin, whole_parts[k].points_begin) << what;
      EXPECT_EQ(parts[0][k].points_end, whole_parts[k].points_end) << what;
      EXPECT_EQ(parts[0][k].lines_begin, whole_parts[k].lines_begin) << what;
      EXPECT_EQ(parts[0][k].lines_end, whole_parts[k].lines_end) << what;
    }
  }
}

TEST_F(ReadShareTest, AHeaderAfterLongCommentsIsStillAHeader) {
  // The header lies in a later share's bytes: only the comments come before it.
  std::string text(4000, ' ');
  for (size_t i = 0; i < text.size(); i += 50) text[i] = '\n', text[i + 1] = '#';
  text += "\neasting northing height\n500000 6000000 1\n500001 6000000 2\n500000 6000001 3\n";
  write("late.xyz", text);
  const InputSet whole = read_whole({path("late.xyz")});
  ASSERT_EQ(whole.points.size(), 3u);
  for (uint32_t count : {2u, 3u, 4u, 7u})
    expect_same(read_shared({path("late.xyz")}, count)[0], whole, std::to_string(count));
}

TEST_F(ReadShareTest, ErrorsNameTheLineOfTheWholeFile) {
  std::string text = dem_text(2000);
  const size_t at = text.size() * 3 / 4;
  const size_t line_start = text.find('\n', at) + 1;
  text.insert(line_start, "500000 6000000 oops\n");
  write("bad.csv", text);
  std::string whole_message;
  try {
    read_whole({path("bad.csv")});
  } catch (const InputError& e) {
    whole_message = e.what();
  }
  ASSERT_NE(whole_message.find("bad.csv:1"), std::string::npos) << whole_message;  // a line number past 1000
  // The share holding the bad line, read alone (the others would wait for it in the exchange).
  for (uint32_t count : {2u, 3u, 5u}) {
    ThreadExchange exchange(count);
    const TextSource src = TextSource::open(path("bad.csv"));
    for (uint32_t i = 0; i < count; ++i) {
      const auto [b, e] = share_lines(src.text(), exchange.share(i));
      if (!(b <= line_start && line_start < e)) continue;
      InputSet in;
      try {
        read_xyz_text(src.text(), path("bad.csv"), in, &exchange.share(i));
        ADD_FAILURE() << "share " << i << " of " << count << " read the bad line";
      } catch (const InputError& err) {
        EXPECT_EQ(std::string(err.what()), whole_message) << "share " << i << " of " << count;
      }
    }
  }
}

TEST_F(ReadShareTest, AWordAtAShareStartAfterPointsIsAnError) {
  // A line that would be a header, but after points: the whole read refuses it, and so must the share that
  // starts with it.
  std::string text = dem_text(500);
  ThreadExchange exchange(2);
  const auto [b, e] = share_lines(text, exchange.share(1));
  const size_t end = text.find('\n', b);
  text.replace(b, end - b, std::string("x,y,z") + std::string(end - b - 5, ' '));
  write("word.csv", text);
  std::string whole_message;
  try {
    read_whole({path("word.csv")});
  } catch (const InputError& err) {
    whole_message = err.what();
  }
  ASSERT_NE(whole_message.find("column 1 is not a number: 'x'"), std::string::npos) << whole_message;
  const TextSource src = TextSource::open(path("word.csv"));
  ASSERT_EQ(share_lines(src.text(), exchange.share(1)).first, b);
  InputSet in;
  try {
    read_xyz_text(src.text(), path("word.csv"), in, &exchange.share(1));
    ADD_FAILURE() << "the word was taken for a header";
  } catch (const InputError& err) {
    EXPECT_EQ(std::string(err.what()), whole_message);
  }
}

TEST_F(ReadShareTest, NothingKeptIsReportedOnceJoined) {
  test::LasFile f;
  f.format = 1;
  for (int i = 0; i < 300; ++i) f.points.push_back({.X = i, .Y = i * 3 % 17, .Z = 1, .cls = uint8_t(i < 200 ? 1 : 7)});
  write("noground.las", test::las_bytes(f));
  std::string whole_message;
  try {
    read_whole({path("noground.las:class=2")});
  } catch (const InputError& e) {
    whole_message = e.what();
  }
  ASSERT_NE(whole_message.find("no point passes the filters (300 points; by class: 1 (200), 7 (100)"),
            std::string::npos)
      << whole_message;
  for (uint32_t count : {2u, 3u}) {
    try {
      read_shared({path("noground.las:class=2")}, count);
      ADD_FAILURE() << count;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), whole_message) << count;
    }
  }
}

TEST_F(ReadShareTest, SharesCoverEveryLineOnce) {
  const std::string text = "a\nbb\n\nccc\r\nd";
  for (uint32_t count = 1; count <= 16; ++count) {
    ThreadExchange exchange(count);
    size_t next = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const auto [b, e] = share_lines(text, exchange.share(i));
      EXPECT_EQ(b, next) << count;
      EXPECT_TRUE(b == 0 || text[b - 1] == '\n') << count;
      next = e;
    }
    EXPECT_EQ(next, text.size()) << count;
  }
}

}  // namespace
