// Never destroy a file, never accept damage silently: the cdtgpu binary on special output paths (devices,
// links, FIFOs, stdout), outputs that are inputs, interrupted runs, damaged shapefiles, unknown z fields and
// lon/lat data across the antimeridian. Each test failed on the code before the fix it pins down.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <shapefil.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "core/projection.hpp"
#include "io/readers.hpp"
#include "tests/binary_test.hpp"

namespace fs = std::filesystem;
using namespace cdtgpu;

namespace {

const std::string kSample = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";

using cdtgpu::test::Result;

class Reliability : public cdtgpu::test::BinaryTest {
 public:
  Reliability() : BinaryTest("cdtgpu_rel_") {}

  // Files in dir whose name contains part.
  size_t files_containing(const std::string& part) const {
    size_t n = 0;
    for (auto& e : fs::directory_iterator(dir))
      if (e.path().filename().string().find(part) != std::string::npos) ++n;
    return n;
  }
  // A device node of our own (major, minor as name's): as root, a broken fix renaming over the real /dev/full
  // would destroy the machine's node (running these tests on the old code did exactly that to /dev/null). Not
  // root: mknod fails, and the real node is used, which a non-root rename cannot replace.
  std::string device(const std::string& name, unsigned minor) const {
    const std::string p = path(name);
    if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(1, minor)) == 0) return p;
    return "/dev/" + name;
  }
  void write_points() const { write("p.xyz", "0 0 1\n10 0 2\n0 10 3\n10 10 4\n5 5 5\n"); }
  std::string tri(const std::string& inputs) const {
    return "triangulate " + inputs + " --backend cgal --crs none -q ";
  }
};

// ---- special output paths ----

TEST_F(Reliability, DevFullFailsWithTheOsErrorAndStaysADevice) {
  write_points();
  const std::string full = device("full", 7);
  Result r = run(tri(path("p.xyz")) + "-o " + full + " --format obj");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find(full + ": write failed: No space left on device"), std::string::npos) << r.err;
  struct stat st {};
  ASSERT_EQ(::stat(full.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << full << " was replaced by a regular file";
  // The same for the stats file.
  r = run(tri(path("p.xyz")) + "-o " + path("t.obj") + " --stats " + full);
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find(full + ": write failed"), std::string::npos) << r.err;
  ASSERT_EQ(::stat(full.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST_F(Reliability, DevNullIsWrittenInPlace) {
  write_points();
  const std::string null = device("null", 3);
  Result r = run(tri(path("p.xyz")) + "-o " + null + " --format ply --stats " + null);
  EXPECT_EQ(r.code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(::stat(null.c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST_F(Reliability, SymlinkKeepsPointingAtItsTargetWhichIsReplaced) {
  write_points();
  fs::create_directories(dir / "real");
  write("real/t.obj", "old\n");
  fs::create_symlink("real/t.obj", dir / "link.obj");
  Result r = run(tri(path("p.xyz")) + "-o " + path("link.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir / "link.obj")) << "the link was replaced by a file";
  EXPECT_EQ(fs::read_symlink(dir / "link.obj"), fs::path("real/t.obj"));
  const std::string mesh = slurp(path("real/t.obj"));
  EXPECT_EQ(mesh.rfind("# ", 0), 0u) << mesh;
  EXPECT_NE(mesh.find("\nf "), std::string::npos);
  EXPECT_EQ(files_containing(".tmp-"), 0u);
  for (auto& e : fs::directory_iterator(dir / "real")) EXPECT_EQ(e.path().filename(), "t.obj");
  // A dangling link: its target is created, the link stays.
  fs::create_symlink("real/new.obj", dir / "dangling.obj");
  r = run(tri(path("p.xyz")) + "-o " + path("dangling.obj"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.obj"));
  EXPECT_EQ(slurp(path("real/new.obj")), mesh);
}

TEST_F(Reliability, FifoIsWrittenInPlace) {
  write_points();
  ASSERT_EQ(::mkfifo(path("pipe.obj").c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(path("pipe.obj")); });
  Result r = run(tri(path("p.xyz")) + "-o " + path("pipe.obj"));
  reader.join();
  EXPECT_EQ(r.code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(::lstat(path("pipe.obj").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced by a regular file";
  ASSERT_EQ(run(tri(path("p.xyz")) + "-o " + path("ref.obj")).code, 0);
  EXPECT_EQ(received, slurp(path("ref.obj")));
}

TEST_F(Reliability, DevStdoutWritesToTheRedirectedStream) {
  write_points();
  ASSERT_EQ(run(tri(path("p.xyz")) + "-o " + path("ref.obj")).code, 0);
  // stdout is our own link to /proc/self/fd/1, as /dev/stdout is (the real one is not risked, see device()).
  fs::create_symlink("/proc/self/fd/1", dir / "stdout");
  const std::string out = path("stdout");
  // Redirected to a file: the bytes land in that file and the file is the one the shell opened.
  Result r = run(tri(path("p.xyz")) + "-o " + out + " --format obj", path("out.obj"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("out.obj")), slurp(path("ref.obj")));
  // Appending (>>) keeps what was there.
  write("log.txt", "before\n");
  r = run(tri(path("p.xyz")) + "-o " + out + " --format obj", std::string(">") += path("log.txt"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(path("log.txt")), std::string("before\n") += slurp(path("ref.obj")));
  EXPECT_TRUE(fs::is_symlink(dir / "stdout"));
  // A pipe.
  std::string cmd = "(";
  cmd += std::string(CDTGPU_BINARY) + " " + tri(path("p.xyz")) + "-o /dev/fd/1 --format obj; echo $? >";
  cmd += path("rc.txt") + ") | cat >" + path("piped.obj");
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(slurp(path("rc.txt")), "0\n");
  EXPECT_EQ(slurp(path("piped.obj")), slurp(path("ref.obj")));
}

TEST_F(Reliability, NoPrjBesideASpecialOutput) {
  // Lon/lat input has a CRS with a .prj: beside a regular file it is written, beside a FIFO or a link to
  // /proc/self/fd/1 (as /dev/stdout is) it is not.
  write("ll.xyz", "150.30 -33.70 1000\n150.32 -33.70 1010\n150.31 -33.72 1005\n");
  ASSERT_EQ(run("triangulate " + path("ll.xyz") + " --backend cgal -q -o " + path("t.obj")).code, 0);
  EXPECT_TRUE(fs::exists(path("t.prj")));
  fs::create_symlink("/proc/self/fd/1", dir / "stdout");
  Result r = run("triangulate " + path("ll.xyz") + " --backend cgal -q --format obj -o " + path("stdout"),
                 path("out.obj"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(path("out.obj")).find("# crs: WGS 84 / UTM zone 56S"), std::string::npos);
  ASSERT_EQ(::mkfifo(path("pipe.obj").c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(path("pipe.obj")); });
  r = run("triangulate " + path("ll.xyz") + " --backend cgal -q -o " + path("pipe.obj"));
  reader.join();
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(path("stdout.prj")));
  EXPECT_FALSE(fs::exists(path("pipe.prj")));
}

TEST_F(Reliability, ReplacedFileKeepsItsPermissions) {
  write_points();
  write("t.obj", "old\n");
  fs::permissions(path("t.obj"), fs::perms(0640));
  ASSERT_EQ(run(tri(path("p.xyz")) + "-o " + path("t.obj")).code, 0);
  EXPECT_EQ(fs::status(path("t.obj")).permissions() & fs::perms::all, fs::perms(0640));
}

// ---- outputs that are inputs ----

TEST_F(Reliability, OutputThatIsAnInputIsRefusedBeforeReading) {
  write_points();
  const std::string before = slurp(path("p.xyz"));
  Result r = run(tri(path("p.xyz")) + "-o " + path("p.xyz") + " --format obj");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("p.xyz"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(path("p.xyz")), before);
  // Another spelling of the same file: a link, ./, a hard link.
  fs::create_symlink("p.xyz", dir / "alias.xyz");
  fs::create_hard_link(dir / "p.xyz", dir / "hard.xyz");
  for (const std::string& out : {path("alias.xyz"), (dir / "." / "p.xyz").string(), path("hard.xyz")}) {
    r = run(tri(path("p.xyz")) + "-o " + out + " --format obj");
    EXPECT_EQ(r.code, 2) << out << ": " << r.err;
  }
  EXPECT_EQ(slurp(path("p.xyz")), before);
  // The stats file too.
  r = run(tri(path("p.xyz")) + "-o " + path("t.obj") + " --stats " + path("p.xyz"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(slurp(path("p.xyz")), before);
  EXPECT_FALSE(fs::exists(path("t.obj")));
  // An output in a folder that does not exist: refused before the work, not after it.
  r = run(tri(path("p.xyz")) + "-o " + path("no/such/t.obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("there is no folder"), std::string::npos) << r.err;
  // Stats and mesh on one path, or both on stdout.
  r = run(tri(path("p.xyz")) + "-o " + path("t.obj") + " --stats " + path("t.obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  r = run(tri(path("p.xyz")) + "-o - --format obj --stats -");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("stdout"), std::string::npos) << r.err;
}

TEST_F(Reliability, OutputPrjThatIsAnInputPrjIsRefused) {
  // contours.ply beside contours.shp would replace contours.prj (geographic) by the output's UTM WKT.
  for (const char* ext : {".shp", ".shx", ".dbf", ".prj"})
    fs::copy_file(kSample + "contours" + ext, dir / (std::string("contours") + ext));
  const std::string prj = slurp(path("contours.prj"));
  Result r = run("triangulate " + path("contours.shp") + " --backend cgal -q -o " + path("contours.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("contours.prj"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(path("contours.prj")), prj);
  EXPECT_FALSE(fs::exists(path("contours.ply")));
  // Writing the .dbf or .shx as the mesh is refused too.
  r = run("triangulate " + path("contours.shp") + " --backend cgal -q --format obj -o " +
          path("contours.dbf"));
  EXPECT_EQ(r.code, 2) << r.err;
}

// ---- interrupted runs ----

// A grid large enough that writing its mesh as text takes a noticeable time (tens of ms).
void write_big_grid(const Reliability& t) {
  std::ostringstream s;
  s << "ncols 400\nnrows 400\nxllcorner 0\nyllcorner 0\ncellsize 1\n";
  for (int j = 0; j < 400; ++j) {
    for (int i = 0; i < 400; ++i) s << ((i * 7 + j * 13) % 101) * 0.25 << ' ';
    s << '\n';
  }
  t.write("big.asc", s.str());
}

// Starts cdtgpu, waits for its temporary output file to appear, sends sig. Returns the wait status, and
// whether the temporary file was seen (if the write finished before we looked, the test says so).
std::pair<int, bool> kill_while_writing(const Reliability& t, int sig) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string out = t.path("old.ply");
    const std::string in = t.path("big.asc");
    ::freopen("/dev/null", "w", stderr);
    ::execl(CDTGPU_BINARY, CDTGPU_BINARY, "triangulate", in.c_str(), "--backend", "cgal", "--crs", "none",
            "--ascii", "-q", "-o", out.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const std::string tmp = t.path("old.ply.tmp-" + std::to_string(pid));
  bool seen = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  int status = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    if (fs::exists(tmp) && fs::file_size(tmp) > 0) {
      seen = true;
      ::kill(pid, sig);
      break;
    }
    if (::waitpid(pid, &status, WNOHANG) == pid) return {status, false};
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  if (!seen) ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return {status, seen};
}

TEST_F(Reliability, SigtermWhileWritingKeepsTheOldOutputAndNoTempFile) {
  write_big_grid(*this);
  write("old.ply", "the old output\n");
  for (int sig : {SIGTERM, SIGINT}) {
    auto [status, seen] = kill_while_writing(*this, sig);
    ASSERT_TRUE(seen) << "the run ended before its temporary file was seen; the grid is too small";
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << status;
    EXPECT_EQ(slurp(path("old.ply")), "the old output\n");
    EXPECT_EQ(files_containing(".tmp-"), 0u) << "temporary file left after signal " << sig;
  }
}

TEST_F(Reliability, SigkillWhileWritingKeepsTheOldOutput) {
  write_big_grid(*this);
  write("old.ply", "the old output\n");
  auto [status, seen] = kill_while_writing(*this, SIGKILL);
  ASSERT_TRUE(seen);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  EXPECT_EQ(slurp(path("old.ply")), "the old output\n");
  // SIGKILL cannot be caught: the stale old.ply.tmp-PID stays (documented in docs/rules.md)...
  EXPECT_EQ(files_containing(".tmp-"), 1u);
  // ... until the same output is written again: nothing locks it any more, so that run removes it and says so.
  write_points();
  const Result r = run("triangulate " + path("p.xyz") + " --backend cgal --crs none -o " + path("old.ply"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("the temporary file of an earlier run that was killed"), std::string::npos) << r.err;
  EXPECT_EQ(files_containing(".tmp-"), 0u);
}

// A temporary file that a run still holds (locked, as every run holds its own until the rename) is another
// run's, perhaps on another host sharing the folder: left alone. Once nothing holds it, it goes.
TEST_F(Reliability, ATemporaryFileStillHeldIsLeftAlone) {
  write_points();
  const std::string tmp = path("t.obj.tmp-4000001");  // a pid no run here has
  write("t.obj.tmp-4000001", "a run's partial output\n");
  write("t.obj.tmp-x1", "not a temporary file of ours\n");
  const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  Result r = run(tri(path("p.xyz")) + "-o " + path("t.obj"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(tmp), "a run's partial output\n");
  ::close(fd);
  r = run(tri(path("p.xyz")) + "-o " + path("t.obj"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_TRUE(fs::exists(path("t.obj.tmp-x1")));
  EXPECT_EQ(files_containing(".tmp-"), 1u);
}

// ---- damaged shapefiles ----

std::string bytes_of(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}
void put_bytes(const std::string& p, const std::string& b) { std::ofstream(p, std::ios::binary) << b; }
uint32_t be32_at(const std::string& b, size_t at) {
  return uint32_t(uint8_t(b[at])) << 24 | uint32_t(uint8_t(b[at + 1])) << 16 |
         uint32_t(uint8_t(b[at + 2])) << 8 | uint8_t(b[at + 3]);
}
void put_be32(std::string& b, size_t at, uint32_t v) {
  for (int k = 0; k < 4; ++k) b[at + k] = char((v >> (24 - 8 * k)) & 0xff);
}

// The 1-based record of the .shp holding byte `at`, from the .shx.
uint64_t record_at(const std::string& shx, size_t at) {
  uint64_t found = 0;
  for (size_t i = 0; 100 + 8 * i + 8 <= shx.size(); ++i)
    if (uint64_t(be32_at(shx, 100 + 8 * i)) * 2 <= at) found = i + 1;
  return found;
}

// Reads path, expects an InputError naming `part` at `record`.
void expect_damage(const std::string& path, const std::string& part, uint64_t record,
                   const ReadOptions& o = {}) {
  InputSet in;
  try {
    read_input(path, o, in);
    ADD_FAILURE() << path << ": accepted; expected an error with '" << part << "' at record " << record;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    EXPECT_EQ(e.record, record) << e.what();
  }
}

class Damage : public Reliability {
 public:
  void copy_sample(const std::string& name) const {
    for (const char* ext : {".shp", ".shx", ".dbf", ".prj"})
      fs::copy_file(kSample + name + ext, dir / (name + ext));
  }
};

TEST_F(Damage, HundredFlippedBytesInTheMiddleNameTheRecord) {
  copy_sample("contours");
  std::string shp = bytes_of(path("contours.shp"));
  const size_t mid = shp.size() / 2;
  for (size_t k = mid; k < mid + 100; ++k) shp[k] = char(~shp[k]);
  put_bytes(path("contours.shp"), shp);
  const uint64_t record = record_at(bytes_of(path("contours.shx")), mid);
  Result r = run("triangulate " + path("contours.shp") + " --backend cgal -q -o " + path("t.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("contours.shp:" + std::to_string(record) + ": corrupt record"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("t.ply")));
}

TEST_F(Damage, FlippedBytesAnywhereAreCaught) {
  // 100 bytes flipped at 40 places through each sample shapefile: every one is refused at the record hit.
  for (const std::string name : {"contours", "buildings"}) {
    copy_sample(name);
    const std::string good = bytes_of(path(name + ".shp")), shx = bytes_of(path(name + ".shx"));
    for (int step = 0; step < 40; ++step) {
      const size_t at = 100 + (good.size() - 200) * size_t(step) / 40;
      std::string bad = good;
      for (size_t k = at; k < at + 100; ++k) bad[k] = char(~bad[k]);
      put_bytes(path(name + ".shp"), bad);
      InputSet in;
      try {
        read_input(path(name + ".shp"), {}, in);
        ADD_FAILURE() << name << ": 100 bytes flipped at " << at << " accepted";
      } catch (const InputError& e) {
        // The damage is in the record holding `at`, or in the next one when it reaches that one's header.
        EXPECT_GE(e.record, record_at(shx, at)) << e.what();
        EXPECT_LE(e.record, record_at(shx, at + 100)) << e.what();
      }
    }
    put_bytes(path(name + ".shp"), good);
  }
}

TEST_F(Damage, RecordHeaderThatDisagreesWithTheShx) {
  copy_sample("contours");
  const std::string shx = bytes_of(path("contours.shx"));
  // Record 3's length in the .shx one word short.
  std::string bad = shx;
  put_be32(bad, 100 + 8 * 2 + 4, be32_at(shx, 100 + 8 * 2 + 4) - 1);
  put_bytes(path("contours.shx"), bad);
  expect_damage(path("contours.shp"), "disagrees with the index", 3);
  // Record 5's offset pointing at record 4.
  bad = shx;
  put_be32(bad, 100 + 8 * 4, be32_at(shx, 100 + 8 * 3));
  put_bytes(path("contours.shx"), bad);
  expect_damage(path("contours.shp"), "disagrees with the index", 5);
  // Record 2's offset past the end of the .shp.
  bad = shx;
  put_be32(bad, 100 + 8, 0x7fffffff);
  put_bytes(path("contours.shx"), bad);
  expect_damage(path("contours.shp"), "outside the file", 2);
}

TEST_F(Damage, PartIndexOutOfRange) {
  copy_sample("buildings");
  std::string shp = bytes_of(path("buildings.shp"));
  const std::string shx = bytes_of(path("buildings.shx"));
  // Record 2's first part starts at vertex 1000 (content: type, box, nParts, nPoints, parts[]).
  const size_t content = size_t(be32_at(shx, 100 + 8)) * 2 + 8;
  const size_t part0 = content + 4 + 32 + 4 + 4;
  shp[part0] = char(0xe8), shp[part0 + 1] = char(0x03);
  put_bytes(path("buildings.shp"), shp);
  expect_damage(path("buildings.shp"), "buildings.shp:2: corrupt", 2);
}

TEST_F(Damage, CoordinateOutsideTheHeaderBox) {
  // A point moved by 1 km, everything else consistent: outside the header's box.
  copy_sample("buildings");
  std::string shp = bytes_of(path("buildings.shp"));
  const std::string shx = bytes_of(path("buildings.shx"));
  const size_t content = size_t(be32_at(shx, 100 + 8 * 6)) * 2 + 8;  // record 7
  const uint32_t parts = uint8_t(shp[content + 36]);
  const size_t x0 = content + 44 + 4 * parts;
  double x;
  std::memcpy(&x, &shp[x0], 8);
  x += 0.01;  // degrees: about 1 km
  std::memcpy(&shp[x0], &x, 8);
  put_bytes(path("buildings.shp"), shp);
  expect_damage(path("buildings.shp"), "buildings.shp:7: corrupt record: vertex 1", 7);
}

// ---- --z-field that no input has ----

TEST_F(Damage, ZFieldThatNoShapefileHasIsAnError) {
  copy_sample("contours");
  copy_sample("buildings");
  const std::string both = path("contours.shp") + " " + path("buildings.shp");
  Result r = run("triangulate " + both + " --z-field NOPE --backend cgal -q -o " + path("t.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no input shapefile has the z field NOPE"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("contours.dbf (fields: ELEV)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(fields: ID, GROUND, HEIGHT)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("t.ply")));
  // The README's run: contours have ELEV, the footprints do not and keep their own z (said at info level).
  r = run("triangulate " + both + " " + kSample + "dem.xyz --z-field ELEV --backend cgal -o " +
          path("t.ply"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("buildings.shp: no field ELEV"), std::string::npos) << r.err;
  // The contours' .dbf missing: no input has ELEV.
  fs::remove(path("contours.dbf"));
  r = run("triangulate " + path("contours.shp") + " --z-field ELEV --backend cgal -q -o " + path("u.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no attribute file"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ELEV"), std::string::npos) << r.err;
  // No shapefile at all.
  write_points();
  r = run(tri(path("p.xyz")) + "--z-field ELEV -o " + path("v.ply"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("no input is a shapefile"), std::string::npos) << r.err;
}

// ---- lon/lat across the antimeridian, and lon/lat out of range ----

TEST(Antimeridian, ZoneOfTheUnwrappedCentre) {
  // Fiji, both sides of 180: the mean longitude is 0 (zone 31, half the globe away); the centre is 180.
  InputSet in;
  in.points = {{179.9, -16.1, 0}, {-179.9, -16.3, 0}, {179.95, -16.4, 0}, {-179.85, -16.0, 0}};
  const Crs crs = choose_crs(in, parse_crs("auto"));
  EXPECT_TRUE(crs.zone == 1 || crs.zone == 60) << crs.name;
  EXPECT_FALSE(crs.north);
  project(in, crs);
  // 0.25 degree of longitude at 16S is about 26.7 km: projected, the points stay that close.
  for (const Point3& p : in.points) {
    EXPECT_NEAR(p.x, 500000, 400000) << p.x;
    EXPECT_NEAR(std::hypot(p.x - in.points[0].x, p.y - in.points[0].y), 20000, 20000);
  }
  // Data on one side is unchanged: Katoomba still goes to zone 56.
  InputSet k;
  k.points = {{150.30, -33.70, 0}, {150.32, -33.72, 0}};
  EXPECT_EQ(choose_crs(k, parse_crs("auto")).zone, 56);
}

TEST_F(Reliability, AntimeridianDataIsProjectedToItsOwnZone) {
  write("fiji.xyz", "179.9 -16.1 1\n-179.9 -16.3 2\n179.95 -16.4 3\n-179.85 -16.0 4\n180 -16.2 5\n");
  Result r = run("triangulate " + path("fiji.xyz") + " --backend cgal -o " + path("t.obj") + " --stats " +
                 path("s.json"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("antimeridian"), std::string::npos) << r.err;
  const std::string crs = nlohmann::json::parse(slurp(path("s.json")))["crs"];
  EXPECT_TRUE(crs == "WGS 84 / UTM zone 1S" || crs == "WGS 84 / UTM zone 60S") << crs;
  EXPECT_EQ(run("verify " + path("t.obj") + " " + path("fiji.xyz")).code, 0);
}

TEST_F(Reliability, LatitudeBeyond90IsNotSilent) {
  // Without a .prj: kept as projected coordinates, with a warning.
  write("ll.xyz", "150.30 -95.70 1\n150.32 -33.70 2\n150.31 -33.72 3\n");
  Result r = run("triangulate " + path("ll.xyz") + " --backend cgal -o " + path("t.obj"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("latitude"), std::string::npos) << r.err;
  // A shapefile whose .prj says geographic: an error naming the file and the record.
  SHPHandle shp = SHPCreate(path("pts").c_str(), SHPT_POINT);
  ASSERT_NE(shp, nullptr);
  const double xs[] = {150.30, 150.32, 150.31}, ys[] = {-33.70, -95.70, -33.72};
  for (int i = 0; i < 3; ++i) {
    SHPObject* o = SHPCreateSimpleObject(SHPT_POINT, 1, &xs[i], &ys[i], nullptr);
    SHPWriteObject(shp, -1, o);
    SHPDestroyObject(o);
  }
  SHPClose(shp);
  fs::copy_file(kSample + "contours.prj", dir / "pts.prj");
  r = run("triangulate " + path("pts.shp") + " --backend cgal -o " + path("u.obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("pts.shp:2: vertex 1 (150.32 -95.7) is not a longitude/latitude"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("u.obj")));
}

TEST_F(Reliability, GeographicPrjWithProjectedCoordinatesIsAnError) {
  // Contours in lon/lat (geographic .prj) with DEM points in metres: not one coordinate system.
  for (const char* ext : {".shp", ".shx", ".dbf", ".prj"})
    fs::copy_file(kSample + "contours" + ext, dir / (std::string("contours") + ext));
  write("dem.xyz", "273741 5796489 10\n274741 5797489 12\n273800 5796500 11\n");
  Result r = run("triangulate " + path("contours.shp") + " " + path("dem.xyz") + " --backend cgal -o " +
                 path("t.obj"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("contours.shp: its .prj says lon/lat"), std::string::npos) << r.err;
}

}  // namespace
