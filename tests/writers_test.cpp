// Writers and the mesh reader: exact round trips in every format, the exact text of a small mesh, empty
// meshes, whole-or-nothing files, the .prj beside the output, and readable errors from bad mesh files.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cfloat>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>
#include <tuple>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "core/triangle_spans.hpp"
#include "io/writers.hpp"

namespace cdtgpu {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test, removed afterwards.
class WritersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("cdtgpu_writers_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string to_string(const Mesh& mesh, const Crs& crs, const WriteOptions& options) {
  std::ostringstream out;
  write_mesh(mesh, crs, options, out);
  return out.str();
}

Crs named_crs(const std::string& name) {
  Crs c;
  c.name = name;
  return c;
}

// Bit-for-bit equality, so -0.0 and 0.0 count as different.
void expect_identical(const Mesh& a, const Mesh& b, const std::string& what) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
  for (size_t i = 0; i < a.vertices.size(); ++i)
    EXPECT_EQ(std::memcmp(&a.vertices[i], &b.vertices[i], sizeof(Point3)), 0)
        << what << ": vertex " << i << " (" << a.vertices[i].x << " " << a.vertices[i].y << " " << a.vertices[i].z
        << ") read back as (" << b.vertices[i].x << " " << b.vertices[i].y << " " << b.vertices[i].z << ")";
  EXPECT_EQ(a.triangles, b.triangles) << what;
}

// Doubles that are easy to get wrong in text: negative zero, the smallest subnormal, the extremes, values with
// no short decimal form, integers just above 2^53. Vertices in canonical (x, y) order.
Mesh awkward_mesh() {
  Mesh m;
  m.vertices = {
      {-DBL_MAX, 0.1, -0.0},
      {-0.0, 1e-300, 4.9406564584124654e-324},
      {0.1, 6123456.789, 9007199254740994.0},
      {1.0 / 3, -2.2250738585072014e-308, 0.1 + 0.2},
      {6123456.789, 1e22, 123456789012345678.0},
      {9007199254740996.0, -0.1, DBL_MAX},
  };
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
  return m;
}

// Enough vertices that the output passes the writer's 1 MiB buffer several times.
Mesh random_mesh(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Mesh m;
  auto random_double = [&] {
    double d;
    do d = std::bit_cast<double>(rng());
    while (!std::isfinite(d));
    return d;
  };
  for (size_t i = 0; i < n; ++i) {
    // Half plain GIS-like values, half arbitrary bit patterns.
    if (i % 2)
      m.vertices.push_back({random_double(), random_double(), random_double()});
    else
      m.vertices.push_back({double(rng() % 1000000000) / 1000, double(rng() % 7000000000) / 1000,
                            double(rng() % 2000000) / 1000});
  }
  auto key = [](const Point3& p) {
    return std::make_tuple(p.x, p.y, p.z, std::bit_cast<uint64_t>(p.x), std::bit_cast<uint64_t>(p.y),
                           std::bit_cast<uint64_t>(p.z));
  };
  std::sort(m.vertices.begin(), m.vertices.end(), [&](const Point3& a, const Point3& b) { return key(a) < key(b); });
  for (uint32_t i = 0; i + 2 < n; ++i) m.triangles.push_back({i, i + 2, i + 1});
  return m;
}

struct Case {
  const char* file;
  WriteOptions options;
};

std::vector<Case> all_formats() {
  return {{"mesh.obj", {MeshFormat::Obj, false, false}},
          {"mesh.ply", {MeshFormat::Ply, false, false}},
          {"mesh_ascii.ply", {MeshFormat::Ply, true, false}},
          {"mesh.wkt", {MeshFormat::Wkt, false, false}},
          {"mesh_multi.wkt", {MeshFormat::Wkt, false, true}}};
}

TEST_F(WritersTest, EveryFormatRoundTripsAwkwardDoublesExactly) {
  const Mesh mesh = awkward_mesh();
  const Crs crs = named_crs("WGS 84 / UTM zone 55S");
  for (const Case& c : all_formats()) {
    write_mesh_file(mesh, crs, c.options, path(c.file));
    expect_identical(mesh, read_mesh_file(path(c.file)), c.file);
  }
}

TEST_F(WritersTest, EveryFormatRoundTripsALargeMeshExactly) {
  const Mesh mesh = random_mesh(30000, 7);
  for (const Case& c : all_formats()) {
    write_mesh_file(mesh, Crs{}, c.options, path(c.file));
    expect_identical(mesh, read_mesh_file(path(c.file)), c.file);
  }
}

// Text formats are formatted on all cores in blocks: the bytes equal one thread's, and a bad index deep in the
// faces is still reported as the first bad triangle, with nothing written.
TEST_F(WritersTest, EveryFormatTheSameBytesOnOneThreadAndOnAll) {
  const Mesh mesh = random_mesh(120000, 9);
  std::vector<Case> cases = all_formats();
  cases.push_back({"mesh.xml", {MeshFormat::LandXml, false, false}});
  cases.push_back({"mesh.2dm", {MeshFormat::Sms2dm, false, false}});
  setenv("SOURCE_DATE_EPOCH", "1700000000", 1);  // the LandXML date and time
  for (const Case& c : cases) {
    std::ostringstream all, one;
    write_mesh(mesh, named_crs("GDA2020 / MGA zone 56"), c.options, all);
    tbb::task_arena(1).execute([&] { write_mesh(mesh, named_crs("GDA2020 / MGA zone 56"), c.options, one); });
    EXPECT_GT(all.str().size(), size_t(2) << 20) << c.file << ": more than one block";
    EXPECT_TRUE(all.str() == one.str()) << c.file;
  }
  unsetenv("SOURCE_DATE_EPOCH");
  Mesh bad = mesh;
  bad.triangles[100000][1] = 9999999;
  bad.triangles[110000][2] = 8888888;
  for (const Case& c : cases) {
    try {
      write_mesh_file(bad, Crs{}, c.options, path(c.file));
      ADD_FAILURE() << c.file << ": a bad index was written";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("triangle 100000 has vertex index 9999999"), std::string::npos)
          << c.file << ": " << e.what();
    }
    EXPECT_FALSE(fs::exists(path(c.file))) << c.file;
  }
}

// A tiled run's triangles written where they lie (TriangleSpans over its tiles' runs, io/writers'
// write_mesh_file of spans): the bytes of the one array in OBJ and both PLYs, to a file and to stdout's writer,
// whatever the spans (one triangle, thousands, empty ones between, a span across the writer's blocks).
TEST_F(WritersTest, TrianglesInSpansGiveTheOneArraysBytes) {
  const Mesh mesh = random_mesh(120000, 11);
  std::mt19937_64 rng(5);
  std::vector<std::span<const Triangle>> spans;
  const std::span<const Triangle> all(mesh.triangles);
  for (size_t at = 0; at < all.size();) {
    const size_t k = rng() % 4 == 0 ? 0 : rng() % 512 == 0 ? rng() % 30000 : 1 + rng() % 3;
    spans.push_back(all.subspan(at, std::min(k, all.size() - at)));
    at += spans.back().size();
  }
  std::erase_if(spans, [](std::span<const Triangle> s) { return s.empty(); });  // TriangleSpans holds none empty
  const TriangleSpans in_spans(spans);
  ASSERT_GT(in_spans.span_count(), 1000u);
  for (const Case& c : all_formats()) {
    if (!vertices_first(c.options)) continue;
    write_mesh_file(mesh, named_crs("GDA2020 / MGA zone 56"), c.options, path(c.file));
    write_mesh_file(mesh.vertices, in_spans, named_crs("GDA2020 / MGA zone 56"), c.options, path(c.file) + ".spans");
    EXPECT_TRUE(slurp(path(c.file)) == slurp(path(c.file) + ".spans")) << c.file;
    std::ostringstream faces;
    write_mesh_faces(in_spans, mesh.vertices.size(), c.options, faces);
    EXPECT_NE(slurp(path(c.file)).find(faces.str()), std::string::npos) << c.file << ": the faces alone";
  }
}

// A small mesh whose text is worked out by hand below.
Mesh small_mesh() {
  Mesh m;
  m.vertices = {{0.1, 0, 100}, {0.1, 10, 99}, {10, 0.5, 101.25}, {10, 10, 1e-7}};
  m.triangles = {{0, 2, 3}, {0, 3, 1}};
  return m;
}

TEST_F(WritersTest, ObjTextIsExact) {
  EXPECT_EQ(to_string(small_mesh(), named_crs("WGS 84 / UTM zone 55S"), {MeshFormat::Obj, false, false}),
            "# crs: WGS 84 / UTM zone 55S\n"
            "v 0.1 0 100\n"
            "v 0.1 10 99\n"
            "v 10 0.5 101.25\n"
            "v 10 10 1e-07\n"
            "f 1 3 4\n"
            "f 1 4 2\n");
}

const char* kPlyHeaderTail =
    "comment crs WGS 84 / UTM zone 55S\n"
    "element vertex 4\n"
    "property double x\n"
    "property double y\n"
    "property double z\n"
    "element face 2\n"
    "property list uchar uint vertex_indices\n"
    "end_header\n";

TEST_F(WritersTest, PlyAsciiTextIsExact) {
  EXPECT_EQ(to_string(small_mesh(), named_crs("WGS 84 / UTM zone 55S"), {MeshFormat::Ply, true, false}),
            std::string("ply\nformat ascii 1.0\n") + kPlyHeaderTail +
                "0.1 0 100\n"
                "0.1 10 99\n"
                "10 0.5 101.25\n"
                "10 10 1e-07\n"
                "3 0 2 3\n"
                "3 0 3 1\n");
}

TEST_F(WritersTest, PlyBinaryIsLittleEndianDoublesAndUcharUintFaces) {
  const std::string bytes = to_string(small_mesh(), named_crs("WGS 84 / UTM zone 55S"), {MeshFormat::Ply, false, false});
  const std::string header = std::string("ply\nformat binary_little_endian 1.0\n") + kPlyHeaderTail;
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_EQ(bytes.size(), header.size() + 4 * 24 + 2 * 13);
  // 0.1 is 0x3FB999999999999A; little-endian puts the low byte first.
  const unsigned char first_x[8] = {0x9A, 0x99, 0x99, 0x99, 0x99, 0x99, 0xB9, 0x3F};
  EXPECT_EQ(std::memcmp(bytes.data() + header.size(), first_x, 8), 0);
  // The last face: count 3, then 0, 3, 1 as 32-bit little-endian.
  const unsigned char last_face[13] = {3, 0, 0, 0, 0, 3, 0, 0, 0, 1, 0, 0, 0};
  EXPECT_EQ(std::memcmp(bytes.data() + bytes.size() - 13, last_face, 13), 0);
}

TEST_F(WritersTest, WktTextIsExact) {
  const Mesh mesh = small_mesh();
  const std::string rings =
      "(((0.1 0 100, 10 0.5 101.25, 10 10 1e-07, 0.1 0 100)), "
      "((0.1 0 100, 10 10 1e-07, 0.1 10 99, 0.1 0 100)))\n";
  EXPECT_EQ(to_string(mesh, named_crs("x"), {MeshFormat::Wkt, false, false}), "TIN Z " + rings);
  EXPECT_EQ(to_string(mesh, named_crs("x"), {MeshFormat::Wkt, false, true}), "MULTIPOLYGON Z " + rings);
}

TEST_F(WritersTest, EmptyMeshesAreWrittenValidly) {
  Mesh points_only = small_mesh();
  points_only.triangles.clear();
  const Crs crs = named_crs("none");
  EXPECT_EQ(to_string(points_only, crs, {MeshFormat::Obj, false, false}),
            "# crs: none\nv 0.1 0 100\nv 0.1 10 99\nv 10 0.5 101.25\nv 10 10 1e-07\n");
  EXPECT_EQ(to_string(points_only, crs, {MeshFormat::Wkt, false, false}), "TIN Z EMPTY\n");
  EXPECT_EQ(to_string(points_only, crs, {MeshFormat::Wkt, false, true}), "MULTIPOLYGON Z EMPTY\n");
  const std::string ply = to_string(points_only, crs, {MeshFormat::Ply, true, false});
  EXPECT_NE(ply.find("element face 0\n"), std::string::npos) << ply;

  // OBJ and PLY keep the vertices; WKT has nothing but the empty geometry.
  for (const Case& c : all_formats()) {
    write_mesh_file(points_only, crs, c.options, path(c.file));
    const Mesh back = read_mesh_file(path(c.file));
    if (c.options.format == MeshFormat::Wkt) {
      EXPECT_TRUE(back.vertices.empty()) << c.file;
      EXPECT_TRUE(back.triangles.empty()) << c.file;
    } else {
      expect_identical(points_only, back, c.file);
    }
  }
  write_mesh_file(Mesh{}, crs, {MeshFormat::Ply, false, false}, path("nothing.ply"));
  const Mesh nothing = read_mesh_file(path("nothing.ply"));
  EXPECT_TRUE(nothing.vertices.empty());
  EXPECT_TRUE(nothing.triangles.empty());
}

TEST_F(WritersTest, WritingIntoAMissingFolderFailsAndCreatesNothing) {
  const std::string target = path("no_such_folder/tin.ply");
  EXPECT_ANY_THROW(write_mesh_file(small_mesh(), Crs{}, {MeshFormat::Ply, false, false}, target));
  EXPECT_FALSE(fs::exists(path("no_such_folder")));
  EXPECT_TRUE(entries().empty());
}

TEST_F(WritersTest, AWriterThatThrowsMidwayLeavesNoFileAndKeepsTheOldOne) {
  // The bad index is in the last triangle: megabytes have reached the temporary file when the writer throws.
  Mesh bad = random_mesh(60000, 3);
  bad.triangles.back()[2] = uint32_t(bad.vertices.size());
  InputSet one_point;
  one_point.points = {{150.31, -33.71, 0}};
  Crs crs = choose_crs(one_point, parse_crs("auto"));
  ASSERT_FALSE(crs.wkt.empty());
  for (const Case& c : all_formats()) {
    EXPECT_THROW(write_mesh_file(bad, crs, c.options, path(c.file)), std::runtime_error) << c.file;
    EXPECT_TRUE(entries().empty()) << c.file << ": " << (entries().empty() ? "" : entries()[0]);
  }
  {
    std::ofstream old(path("tin.obj"));
    old << "old\n";
  }
  EXPECT_THROW(write_mesh_file(bad, crs, {MeshFormat::Obj, false, false}, path("tin.obj")), std::runtime_error);
  EXPECT_EQ(slurp(path("tin.obj")), "old\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"tin.obj"});
}

TEST_F(WritersTest, ReplacedFilesAreReleased) {
  // The file a write replaces is handed to a short-lived child (/bin/true) that frees its pages and blocks as
  // it exits: none of its descriptors may stay open here, every name holds its last contents, and the
  // children are reaped as writes go on (not one zombie per replaced file).
  auto descriptors = [] {
    return size_t(std::distance(fs::directory_iterator("/proc/self/fd"), fs::directory_iterator{}));
  };
  auto children = [] {  // processes whose parent is this one, zombies included
    size_t n = 0;
    for (const auto& e : fs::directory_iterator("/proc")) {
      const std::string name = e.path().filename().string();
      if (name.find_first_not_of("0123456789") != std::string::npos) continue;
      std::ifstream stat(e.path() / "stat");
      std::string line;
      std::getline(stat, line);
      const size_t close = line.rfind(')');
      if (close == std::string::npos) continue;
      std::istringstream rest(line.substr(close + 2));
      std::string state;
      long ppid = 0;
      rest >> state >> ppid;
      n += ppid == long(::getpid());
    }
    return n;
  };
  const Mesh mesh = random_mesh(20000, 5);
  const WriteOptions ply{MeshFormat::Ply, false, false};
  write_mesh_file(mesh, Crs{}, ply, path("a.ply"));
  const std::string first = slurp(path("a.ply"));
  const size_t before = descriptors();
  for (int i = 0; i < 20; ++i) {
    write_mesh_file(mesh, Crs{}, ply, path("a.ply"));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // time for the last child to exit
  }
  for (int wait = 0; wait < 500 && descriptors() > before; ++wait)  // without /bin/true: a thread closes it
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(descriptors(), before);
  if (fs::exists("/bin/true")) {
    EXPECT_LE(children(), 2u);
  }
  EXPECT_EQ(slurp(path("a.ply")), first);
  EXPECT_EQ(entries(), std::vector<std::string>{"a.ply"});
}

TEST_F(WritersTest, PrjIsWrittenBesideTheMeshWhenTheCrsHasWkt) {
  InputSet in;
  in.points = {{150.31, -33.71, 1000}};
  const Crs crs = choose_crs(in, parse_crs("EPSG:7856"));
  write_mesh_file(small_mesh(), crs, {MeshFormat::Wkt, false, false}, path("tin.wkt"));
  EXPECT_EQ(entries(), (std::vector<std::string>{"tin.prj", "tin.wkt"}));
  EXPECT_EQ(slurp(path("tin.prj")), crs.wkt);
  EXPECT_EQ(slurp(path("tin.prj")).rfind("PROJCS[\"GDA2020_MGA_Zone_56\"", 0), 0u);

  fs::remove(path("tin.prj"));
  fs::remove(path("tin.wkt"));
  write_mesh_file(small_mesh(), named_crs("none"), {MeshFormat::Obj, false, false}, path("plain.obj"));
  EXPECT_EQ(entries(), std::vector<std::string>{"plain.obj"});
}

TEST(Formats, FromExtensionAndName) {
  EXPECT_EQ(format_from_extension("a/b/tin.obj"), MeshFormat::Obj);
  EXPECT_EQ(format_from_extension("tin.PLY"), MeshFormat::Ply);
  EXPECT_EQ(format_from_extension("tin.wkt"), MeshFormat::Wkt);
  EXPECT_THROW(format_from_extension("tin.stl"), UsageError);
  EXPECT_THROW(format_from_extension("tin"), UsageError);
  EXPECT_EQ(parse_format("obj"), MeshFormat::Obj);
  EXPECT_EQ(parse_format("PLY"), MeshFormat::Ply);
  EXPECT_EQ(parse_format("wkt"), MeshFormat::Wkt);
  EXPECT_THROW(parse_format("off"), UsageError);
  EXPECT_THROW(parse_format(""), UsageError);
}

// Writes text to a file and expects read_mesh_file to reject it with an InputError naming the file, the given
// record (line; 0 when not line-based) and containing `words`.
void expect_rejected(const std::string& file, const std::string& text, uint64_t record, const std::string& words) {
  {
    std::ofstream out(file, std::ios::binary);
    out << text;
  }
  try {
    read_mesh_file(file);
    ADD_FAILURE() << file << " was accepted:\n" << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file, file);
    EXPECT_EQ(e.record, record) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST_F(WritersTest, BadMeshFilesAreRejectedWithFileAndLine) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_rejected(path("a.obj"), v + "f 1 2 4\n", 4, "face index 4");
  expect_rejected(path("b.obj"), v + "v 1 1 0\nf 1 2 4 3\n", 5, "4 vertices");
  expect_rejected(path("c.obj"), "# x\nv 0 0 zero\n", 2, "bad coordinate");
  expect_rejected(path("d.obj"), v + "f 1 2 3\ncurv 0 1\n", 5, "unknown OBJ statement");
  expect_rejected(path("e.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
                                 "property double z\nend_header\n0 0 0\n1 1\n",
                  9, "file ends inside vertex 1");
  expect_rejected(path("f.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
                                 "element face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0\n3 0 0 1\n",
                  0, "face 0: vertex index 1 out of range");
  expect_rejected(path("g.wkt"), "TIN Z (((0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 0)))\n", 1, "not a triangle");
  expect_rejected(path("h.wkt"), "TIN Z (((0 0 0, 1 0 0, 1 1 0, 0 0 0)),\n ((0 0 0, 1 1 0, 0 1 0, 0 0 1)))\n", 2,
                  "not a closed triangle");
  expect_rejected(path("i.wkt"), "POLYGON Z ((0 0 0, 1 0 0, 1 1 0, 0 0 0))\n", 1, "expected TIN Z");
  expect_rejected(path("j.stl"), "solid\n", 0, "unknown mesh format");

  // A binary PLY cut short in the faces.
  Mesh mesh = small_mesh();
  write_mesh_file(mesh, Crs{}, {MeshFormat::Ply, false, false}, path("cut.ply"));
  const std::string bytes = slurp(path("cut.ply"));
  expect_rejected(path("cut.ply"), bytes.substr(0, bytes.size() - 5), 0, "file ends inside face 1");
}

TEST_F(WritersTest, ReaderTakesCommonVariantsOfOtherTools) {
  // OBJ with v/vt/vn faces, negative (relative) indices and groups; PLY with float coordinates, int indices and
  // extra properties; WKT POLYHEDRALSURFACE Z without the final newline.
  std::ofstream(path("a.obj")) << "o tin\nv 0 0 0\nv 1 0 0\nv 0 1 0.5\nvn 0 0 1\nf 1//1 2//1 3//1\nf -3 -2 -1\n";
  const Mesh a = read_mesh_file(path("a.obj"));
  EXPECT_EQ(a.vertices.size(), 3u);
  EXPECT_EQ(a.triangles, (Triangles{{0, 1, 2}, {0, 1, 2}}));
  EXPECT_EQ(a.vertices[2].z, 0.5);

  std::ofstream(path("b.ply")) << "ply\nformat ascii 1.0\ncomment hi\nelement vertex 3\nproperty float x\n"
                                  "property float y\nproperty float z\nproperty uchar red\nelement face 1\n"
                                  "property list uchar int vertex_index\nend_header\n0 0 0 7\n1.5 0 0 7\n0 1 2 7\n"
                                  "3 0 1 2\n";
  const Mesh b = read_mesh_file(path("b.ply"));
  EXPECT_EQ(b.vertices, (Points{{0, 0, 0}, {1.5, 0, 0}, {0, 1, 2}}));
  EXPECT_EQ(b.triangles, (Triangles{{0, 1, 2}}));

  std::ofstream(path("c.wkt")) << "POLYHEDRALSURFACE Z (((1 0 0, 1 1 0, 0 0 0, 1 0 0)))";
  const Mesh c = read_mesh_file(path("c.wkt"));
  // Vertices come back in (x, y) order: (0 0), (1 0), (1 1).
  EXPECT_EQ(c.vertices, (Points{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
  EXPECT_EQ(c.triangles, (Triangles{{1, 2, 0}}));
}

}  // namespace
}  // namespace cdtgpu
