// io/mapped_files: files held in memory read like files on disk, by the shapefile reader too (the fuzz target
// reads its shapefiles that way, fuzz/harness.hpp).
#include <gtest/gtest.h>

#include <cerrno>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/mapped_files.hpp"
#include "io/readers.hpp"

using namespace cdtgpu;

namespace {

const std::string kSample = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";

std::string slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

TEST(MappedFiles, MemoryFileIsAFileUntilRemoved) {
  const std::string p = "/no-such-dir-cdtgpu/held.bin";
  EXPECT_FALSE(files::is_file(p));
  EXPECT_EQ(files::open(p), nullptr);
  files::put_memory_file(p, "abc");
  EXPECT_TRUE(files::is_file(p));
  {
    files::Open f(files::open(p));
    ASSERT_TRUE(f);
    files::put_memory_file(p, "replaced");  // an open file keeps the bytes it was opened with
    EXPECT_EQ(f->bytes(), "abc");
  }
  EXPECT_EQ(files::Open(files::open(p))->bytes(), "replaced");
  files::remove_memory_file(p);
  EXPECT_FALSE(files::is_file(p));
}

TEST(MappedFiles, DiskFileIsMappedWhole) {
  files::Open f(files::open(kSample + "dem.xyz"));
  ASSERT_TRUE(f);
  EXPECT_EQ(f->bytes(), slurp(kSample + "dem.xyz"));
  errno = 0;
  EXPECT_EQ(files::open(kSample + "missing.xyz"), nullptr);
  EXPECT_EQ(errno, ENOENT);
}

void expect_same(const InputSet& a, const InputSet& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_EQ(a.lines.size(), b.lines.size());
  for (size_t i = 0; i < a.lines.size(); ++i) {
    ASSERT_EQ(a.lines[i].points.size(), b.lines[i].points.size()) << i;
    EXPECT_EQ(a.lines[i].closed, b.lines[i].closed);
    EXPECT_EQ(a.lines[i].record, b.lines[i].record);
    for (size_t k = 0; k < a.lines[i].points.size(); ++k) {
      EXPECT_EQ(a.lines[i].points[k].x, b.lines[i].points[k].x);
      EXPECT_EQ(a.lines[i].points[k].y, b.lines[i].points[k].y);
      EXPECT_EQ(a.lines[i].points[k].z, b.lines[i].points[k].z);
    }
  }
  EXPECT_EQ(a.source_crs_wkt, b.source_crs_wkt);
}

// The sample's contours (with their .prj and the z field from the .dbf) read from memory as from disk; without
// the .dbf in memory the z field is missing, as it would be on disk.
TEST(MappedFiles, ShapefileFromMemoryReadsAsFromDisk) {
  ReadOptions o;
  o.z_field = "ELEV";
  InputSet disk, memory;
  read_shapefile(kSample + "contours.shp", o, disk);
  ASSERT_GT(disk.lines.size(), 10u);
  const std::string base = "/cdtgpu-memory-test/contours";
  for (const char* ext : {".shp", ".shx", ".dbf", ".prj"})
    files::put_memory_file(base + ext, slurp(kSample + "contours" + ext));
  read_shapefile(base + ".shp", o, memory);
  expect_same(disk, memory);

  files::remove_memory_file(base + ".dbf");
  InputSet no_dbf;
  o.z_field = "NOPE";
  EXPECT_THROW(read_shapefile(base + ".shp", o, no_dbf), InputError);
  for (const char* ext : {".shp", ".shx", ".prj"}) files::remove_memory_file(base + ext);
  EXPECT_THROW(read_shapefile(base + ".shp", o, no_dbf), InputError);
}

}  // namespace
