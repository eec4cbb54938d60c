// Test helper for the tests that run the cdtgpu binary (cli_test, batch_test, reliability_test): a temporary
// folder of the test's own, files in it, and the binary run through /bin/sh with its exit code and stderr.
//
//   class Cli : public cdtgpu::test::BinaryTest {
//    public:
//     Cli() : BinaryTest("cdtgpu_cli_") {}
//   };
//   TEST_F(Cli, X) { write("a.xyz", "0 0 1\n..."); Result r = run("triangulate " + path("a.xyz") + " -o -"); }
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace cdtgpu::test {

struct Result {
  int code;
  std::string err;
};

class BinaryTest : public ::testing::Test {
 public:
  std::filesystem::path root;  // removed after the test
  std::filesystem::path dir;   // root, or `sub` below it

  std::string path(const std::string& name) const { return (dir / name).string(); }

  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }

  static std::string slurp(const std::string& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  }

  // The binary with `args` (through /bin/sh: quoting means what a shell makes of it), stdout to `stdout_to`.
  Result run(const std::string& args, const std::string& stdout_to = "/dev/null") const {
    const std::string err = path("stderr.txt");
    const std::string cmd = std::string(CDTGPU_BINARY) + " " + args + " >" + stdout_to + " 2>" + err;
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(err)};
  }

 protected:
  // The folder: the temp dir / prefix + pid + test name, and `sub` below it (a name with a space, say).
  explicit BinaryTest(std::string prefix, std::string sub = {}) : prefix_(std::move(prefix)), sub_(std::move(sub)) {}

  void SetUp() override {
    root = std::filesystem::temp_directory_path() /
           (prefix_ + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    dir = sub_.empty() ? root : root / sub_;
    std::filesystem::remove_all(root);
    std::filesystem::create_directories(dir);
  }
  void TearDown() override { std::filesystem::remove_all(root); }

 private:
  std::string prefix_, sub_;
};

// 400 DEM points on a 10 m grid, each jittered by up to 1 m (seeded), z = 100 + i + j / 2, in projected metres:
// a CSV with an "x,y,z" header.
// A DEM of side x side points on whole metres (MGA-like coordinates): lines through its vertices pass exactly
// through them.
inline std::string grid_dem_csv(int side) {
  std::ostringstream xyz;
  xyz << "x,y,z\n";
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) xyz << 500000 + i << ',' << 6000000 + j << ',' << 100 + (i * 7 + j * 3) % 11 << '\n';
  return xyz.str();
}

inline std::string jittered_dem_csv(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::ostringstream xyz;
  xyz << "x,y,z\n";
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      xyz << 500000 + i * 10 + u(rng) << ',' << 6000000 + j * 10 + u(rng) << ',' << 100 + i + j * 0.5 << '\n';
  return xyz.str();
}

}  // namespace cdtgpu::test
