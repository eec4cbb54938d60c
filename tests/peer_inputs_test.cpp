// Every input of artem-ogre/CDT's test suite (../shared/data/cdt-peer-inputs) through read_peer_input,
// prepare, the CGAL CDT and verify; plus the reader's error messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/cdt_cgal.hpp"
#include "core/error.hpp"
#include "core/prepare.hpp"
#include "core/verify.hpp"
#include "io/readers.hpp"
#include "tests/peer_inputs.hpp"

namespace cdtgpu {
namespace {

const std::filesystem::path kDir = peer_inputs_dir();

std::vector<std::string> peer_files() {
  std::vector<std::string> names;
  for (const auto& f : peer_input_files()) names.push_back(f.filename().string());
  return names;
}

TEST(PeerInputs, DirectoryHasTheFiles) {
  CDTGPU_SKIP_WITHOUT_PEER_INPUTS();
  EXPECT_GE(peer_files().size(), 30u) << kDir;
}

// Without the folder the suite has no instances; that is a skip, not a failure.
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(PeerInput);

class PeerInput : public ::testing::TestWithParam<std::string> {};

TEST_P(PeerInput, TriangulatesAndVerifies) {
  const std::string path = (kDir / GetParam()).string();
  std::ifstream file(path, std::ios::binary);
  ASSERT_TRUE(file) << path;
  InputSet in;
  read_peer_input(file, path, in);
  const auto t0 = std::chrono::steady_clock::now();
  PreparedInput p = prepare(in);
  CdtResult r = triangulate_cgal(p);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  VerifyReport v = verify_mesh(r.mesh, p);
  std::string msg;
  for (const std::string& f : v.failures) msg += "  " + f + "\n";
  EXPECT_TRUE(v.ok()) << path << ":\n" << msg;
  EXPECT_EQ(v.steiner_vertices, r.steiner_points);
  EXPECT_LT(ms, 2000) << "CGAL is slow on " << path;
  RecordProperty("vertices", int(r.mesh.vertices.size()));
  RecordProperty("steiner", int(r.steiner_points));
  if (!p.constraints.empty() && !r.mesh.triangles.empty()) {
    EXPECT_GT(v.constrained_edges, 0u);
  }
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string s = info.param.substr(0, info.param.size() - 4);
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Files, PeerInput, ::testing::ValuesIn(peer_files()), test_name);

// ---------------------------------------------------------------------------------------------------------------
// The reader

InputSet read(const std::string& text) {
  std::istringstream s(text);
  InputSet in;
  read_peer_input(s, "t.txt", in);
  return in;
}

std::string error_of(const std::string& text) {
  try {
    read(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReadPeer, ReadsVerticesAndEdges) {
  InputSet in = read("4 2\r\n0 0\r\n1.5\t0\n\n1 1\n0 1  \n0 2\n1 3\n");
  ASSERT_EQ(in.sources.size(), 1u);
  ASSERT_EQ(in.points.size(), 4u);
  EXPECT_EQ(in.points[1], (Point3{1.5, 0, 0}));
  ASSERT_EQ(in.lines.size(), 2u);
  EXPECT_EQ(in.lines[0].points, (Points{{0, 0, 0}, {1, 1, 0}}));
  EXPECT_EQ(in.lines[1].points, (Points{{1.5, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(in.lines[1].record, 8u);  // line numbers count the blank line
  EXPECT_FALSE(in.lines[0].closed);
}

TEST(ReadPeer, ZeroLengthEdgeBecomesAPoint) {
  InputSet in = read("2 1\n0 0\n0 0\n0 1\n");
  EXPECT_TRUE(in.lines.empty());
  EXPECT_EQ(in.repairs.degenerate_lines, 1u);
}

TEST(ReadPeer, ErrorsNameTheLine) {
  EXPECT_EQ(error_of("3 1\n0 0\n1 0\n0 1\n0 3\n"), "t.txt:5: vertex index 3 out of range (3 vertices)");
  EXPECT_EQ(error_of("2 0\n0 0\n1 x\n"), "t.txt:3: expected a vertex \"x y\"");
  EXPECT_EQ(error_of("2 1\n0 0\n1 1\n"), "t.txt:3: file ends after 0 of 1 edges");
  EXPECT_EQ(error_of("2 1\n0 0\n1 1\n0 -1\n"), "t.txt:4: expected an edge \"i j\" (two vertex indices)");
  EXPECT_EQ(error_of("x\n"), "t.txt:1: expected \"V E\" (two counts)");
  EXPECT_EQ(error_of(""), "t.txt: empty file (expected a first line \"V E\")");
  EXPECT_EQ(error_of("1 0\n0 0\n5 5\n"), "t.txt:3: unexpected line after the 0 edges");
  EXPECT_EQ(error_of("1 0\nnan 0\n"), "t.txt:2: coordinate is not a finite number");
}

}  // namespace
}  // namespace cdtgpu
