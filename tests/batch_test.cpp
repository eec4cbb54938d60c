// cdtgpu batch end to end: the binary on job files, each job's outputs compared with its own `cdtgpu triangulate`.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/gpu_start.hpp"  // kBatchWarmJobs
#include "tests/binary_test.hpp"
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

using cdtgpu::test::Result;

class Batch : public cdtgpu::test::BinaryTest {
 public:
  // A folder name with a space, so that every job line needs its quoting.
  Batch() : BinaryTest("cdtgpu_batch_", "with space") {}

  // The path with a backslash before each space, the third way a job line (and a shell) can keep it one word.
  std::string backslashed(const std::string& name) const {
    std::string p;
    for (char c : path(name)) p += c == ' ' ? std::string("\\ ") : std::string(1, c);
    return p;
  }
  // The path in single quotes, as a shell and a job line both read it.
  // (Appended, not "'" + ...: GCC 12 warns falsely about that with -Wrestrict.)
  std::string q(const std::string& name) const {
    std::string quoted = "'";
    quoted += path(name);
    quoted += "'";
    return quoted;
  }

  // In `dir`. `args` go through /bin/sh, so a job line's quoting means the same here as in a job file.
  Result run(const std::string& args, const std::string& stdin_from = "/dev/null") const {
    const std::string err = path("stderr.txt");
    const std::string cmd = "cd " + q("") + " && " + CDTGPU_BINARY + " " + args + " <'" + stdin_from +
                            "' >/dev/null 2>'" + err + "'";
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(err)};
  }

  nlohmann::json stats(const std::string& name) const { return nlohmann::json::parse(slurp(path(name))); }

  // 400 jittered DEM points, two lines and a building ring in projected metres; a boundary, a lake and a house
  // for the regions; a small ESRI ASCII grid.
  void write_inputs() const {
    write("dem.csv", cdtgpu::test::jittered_dem_csv(11));
    write("lines.wkt",
          "LINESTRING Z (500005 6000005 110, 500100 6000050 111, 500185 6000180 112)\n"
          "POLYGON Z ((500120 6000020 130, 500140 6000020 130, 500140 6000040 130, 500120 6000040 130, "
          "500120 6000020 130))\n");
    write("area.wkt", "POLYGON ((500030 6000030, 500170 6000030, 500170 6000170, 500030 6000170, 500030 6000030))\n");
    write("lake.wkt", "POLYGON ((500060 6000060, 500090 6000060, 500090 6000090, 500060 6000090, 500060 6000060))\n");
    write("house.wkt", "POLYGON ((500150.5 6000100.5, 500160.5 6000100.5, 500160.5 6000110.5, 500150.5 6000110.5))\n");
    std::ostringstream asc;
    asc << "ncols 12\nnrows 9\nxllcorner 501000\nyllcorner 6001000\ncellsize 5\nNODATA_value -9999\n";
    for (int r = 0; r < 9; ++r) {
      for (int c = 0; c < 12; ++c) asc << (r == 4 && c == 4 ? -9999.0 : 50 + r * 0.75 + c * c * 0.1) << ' ';
      asc << '\n';
    }
    write("grid.asc", asc.str());
  }

  void write_jobs(const std::string& name, const std::vector<std::string>& lines) const {
    std::string text;
    for (const std::string& l : lines) text += l + "\n";
    write(name, text);
  }
};

// One job's arguments, its output files named after `prefix` (what a single run and a batch write must match).
struct JobSpec {
  std::function<std::string(const std::string&)> args;
  std::vector<std::string> outputs;  // file names after the prefix
};

// Several jobs mixing formats, options, regions, --max-edge, tiles, grid, contours and preview, and both
// backends (the GPU on whatever device there is; lavapipe in CI): the batch writes every job's bytes and
// --stats counts as the jobs run one by one, and --stats-dir keeps a copy of each job's stats.
TEST_F(Batch, JobsWriteTheBytesOfTheirSingleRuns) {
  write_inputs();
  const std::string s = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  const std::string terrain = q("dem.csv") + " " + q("lines.wkt");
  const std::vector<JobSpec> jobs = {
      {[&](const std::string& p) {
         return "'" + s + "contours.shp:z=ELEV' " + s + "dem.xyz " + s + "buildings.shp:z=min -o " +
                q(p + "sample.ply") + " --grid-out " + q(p + "sample.asc") + " --cell 10 --contours-out " +
                q(p + "sample.wkt") + " --interval 20 --preview " + q(p + "sample.png");
       },
       {"sample.ply", "sample.prj", "sample.asc", "sample.wkt", "sample.png"}},
      {[&](const std::string& p) {
         return q("dem.csv") + " " + q("area.wkt") + ":role=boundary " + q("lake.wkt") + ":role=hole " +
                q("house.wkt") + ":z=drape --max-edge 50 -o " + q(p + "regions.obj");
       },
       {"regions.obj", "regions.prj"}},  // no .prj in either: WKT has no CRS
      {[&](const std::string& p) {
         return terrain + " --backend gpu -o " + q(p + "gpu.wkt") + " --grid-out " + q(p + "gpu.asc") +
                " --cell 2.5 --contours-out " + q(p + "gpu-contours.geojson") + " --interval 2";
       },
       {"gpu.wkt", "gpu.asc", "gpu-contours.geojson"}},
      {[&](const std::string& p) { return q("grid.asc") + " -o " + q(p + "grid.2dm"); }, {"grid.2dm", "grid.prj"}},
      {[&](const std::string& p) {
         return terrain + " --backend cgal --max-tile-points 100 --ascii -o " + q(p + "tiled.ply");
       },
       {"tiled.ply"}},
      {[&](const std::string& p) { return q("dem.csv") + " --backend gpu --crs none -o " + q(p + "gpu2.ply"); },
       {"gpu2.ply"}},
      // The device's buffers kept from the jobs before: regrown for a larger job, then a smaller one whose
      // constraints cross (its Delaunay triangulation may be built twice).
      {[&](const std::string& p) {
         return "'" + s + "contours.shp:z=ELEV' " + s + "dem.xyz --backend gpu -o " + q(p + "gpu3.ply");
       },
       {"gpu3.ply"}},
      {[&](const std::string& p) {
         return terrain + " " + q("cross.wkt") + ":z=drape --backend gpu -o " + q(p + "gpu4.ply");
       },
       {"gpu4.ply"}},
  };
  write("cross.wkt", "LINESTRING (500000 6000100, 500200 6000100)\n");
  std::vector<std::string> lines{"# eight jobs, each also run on its own", ""};
  for (size_t i = 0; i < jobs.size(); ++i) {
    const std::string n = std::to_string(i);
    Result r = run("triangulate " + jobs[i].args("single-") + " -q --stats " + q("single-" + n + ".json"));
    ASSERT_EQ(r.code, 0) << i << ": " << r.err;
    // With or without the command's name first.
    lines.push_back((i == 0 ? "triangulate " : "") + jobs[i].args("batch-") + " --stats " + q("batch-" + n + ".json"));
  }
  write_jobs("jobs.txt", lines);
  Result b = run("batch " + q("jobs.txt") + " --stats-dir " + q("stats dir"));
  ASSERT_EQ(b.code, 0) << b.err;
  for (size_t i = 0; i < jobs.size(); ++i) {
    const std::string n = std::to_string(i);
    for (const std::string& out : jobs[i].outputs) {
      ASSERT_EQ(fs::exists(path("batch-" + out)), fs::exists(path("single-" + out))) << out;
      EXPECT_TRUE(slurp(path("single-" + out)) == slurp(path("batch-" + out))) << out;
    }
    nlohmann::json single = stats("single-" + n + ".json"), batch = stats("batch-" + n + ".json");
    // Its line in the file: two lines before the first job.
    EXPECT_EQ(slurp(path("batch-" + n + ".json")), slurp(path("stats dir/" + std::to_string(i + 3) + ".json")));
    EXPECT_EQ(batch["backend"], single["backend"]) << n;
    EXPECT_EQ(batch["crs"], single["crs"]) << n;
    // The device's buffers stay allocated from one job to the next (that is much of what a batch saves), so a
    // GPU job's peak device memory counts what it keeps for the next and what the jobs before left there.
    if (i == 2 || i >= 5) {
      EXPECT_GE(batch["counts"]["gpu_peak_device_bytes"], single["counts"]["gpu_peak_device_bytes"]);
      batch["counts"].erase("gpu_peak_device_bytes");
      single["counts"].erase("gpu_peak_device_bytes");
    }
    // Whether the build ran before the crossings were found (and again after) depends on the threads' timing.
    if (i == 7) {
      EXPECT_GT(batch["counts"]["steiner_points"], 0);
      for (const char* k : {"gpu_delaunay_built_twice", "gpu_delaunay_rounds"}) {
        batch["counts"].erase(k);
        single["counts"].erase(k);
      }
    }
    EXPECT_EQ(batch["counts"], single["counts"]) << n;
    EXPECT_NE(b.err.find("line " + std::to_string(i + 3) + ": ok, "), std::string::npos) << b.err;
  }
  EXPECT_EQ(stats("batch-2.json")["backend"], "gpu");
  EXPECT_EQ(stats("batch-2.json")["device"], stats("batch-5.json")["device"]);
  EXPECT_NE(b.err.find("batch: 8 jobs, all ok"), std::string::npos) << b.err;
}

// A missing input, an unknown option, a quote left open and a device that does not exist: each named with its
// line, the other jobs written, the failing job's old output untouched, exit code 4.
TEST_F(Batch, BadLinesAreReportedAndTheOthersRun) {
  write_inputs();
  write("keep.ply", "old bytes");
  write_jobs("jobs.txt", {
                             q("dem.csv") + " -o " + q("good1.ply"),
                             q("missing.xyz") + " -o " + q("keep.ply"),
                             q("dem.csv") + " -o " + q("x.ply") + " --no-such-option",
                             q("dem.csv") + " -o '" + path("y.ply"),
                             q("dem.csv") + " --backend gpu --device no-such-gpu -o " + q("dev.ply"),
                             "triangulate " + q("dem.csv") + " -o " + q("good2.ply"),
                         });
  Result r = run("batch " + q("jobs.txt") + " --stats-dir " + q("stats"));
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(fs::exists(path("good1.ply")));
  EXPECT_TRUE(fs::exists(path("good2.ply")));
  EXPECT_EQ(slurp(path("keep.ply")), "old bytes");
  for (const char* name : {"x.ply", "y.ply", "dev.ply", "stats/2.json", "stats/3.json", "stats/4.json",
                           "stats/5.json"})
    EXPECT_FALSE(fs::exists(path(name))) << name;
  EXPECT_TRUE(fs::exists(path("stats/1.json")));
  EXPECT_TRUE(fs::exists(path("stats/6.json")));
  size_t keep_files = 0;
  for (auto& e : fs::directory_iterator(dir)) keep_files += e.path().filename().string().rfind("keep", 0) == 0;
  EXPECT_EQ(keep_files, 1u) << "temporary file left behind";
  for (const std::string& expect : {"line 2: " + path("missing.xyz"), std::string("line 3: "),
                                    std::string("--no-such-option"), std::string("line 4: a single quote is not closed"),
                                    std::string("line 5: "), std::string("no-such-gpu"),
                                    std::string("line 5: failed (exit code 3)"),
                                    std::string("line 2: failed (exit code 2)"), std::string("line 1: ok"),
                                    std::string("line 6: ok"), std::string("4 of 6 jobs failed (lines 2, 3, 4, 5)")})
    EXPECT_NE(r.err.find(expect), std::string::npos) << expect << "\n" << r.err;

  Result none = run("batch " + q("no-jobs.txt"));
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("no-jobs.txt: cannot read the job file"), std::string::npos) << none.err;
}

// Jobs on stdin, with comments, blank lines, CRLF line ends and each kind of quoting; the batch's --backend
// applies to lines without their own.
TEST_F(Batch, JobsFromStdinWithCommentsAndQuoting) {
  write_inputs();
  const std::string d = path("");
  write("jobs.txt",
        "# comment line\n"
        "\n"
        "   \t\n"
        "triangulate \"" + d + "dem.csv\" -o \"" + d + "double \\\"quoted\\\".ply\" -q   # a comment after a job\r\n" +
        "'" + d + "dem.csv' -o " + backslashed("back slash.obj") +
        " --backend gpu --stats '" + d + "b.json'\n" +
        "'" + d + "lines.wkt' -o '" + d + "it'\\''s.wkt' --stats '" + d + "c.json'\n");
  Result r = run("batch - --backend cgal --stats-dir " + q("sd"), path("jobs.txt"));
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(path("double \"quoted\".ply")));
  ASSERT_TRUE(fs::exists(path("back slash.obj")));
  ASSERT_TRUE(fs::exists(path("it's.wkt")));
  EXPECT_EQ(stats("sd/4.json")["backend"], "cgal");
  EXPECT_EQ(stats("b.json")["backend"], "gpu");  // the line's own --backend
  EXPECT_EQ(stats("c.json")["backend"], "cgal");
  ASSERT_EQ(run("triangulate " + q("dem.csv") + " -q -o " + q("one.obj")).code, 0);
  EXPECT_EQ(slurp(path("one.obj")), slurp(path("back slash.obj")));

  // A job reading WKT from stdin while stdin holds the job list.
  write("stdin-jobs.txt", "- -o '" + d + "s.ply'\n");
  r = run("batch -", path("stdin-jobs.txt"));
  EXPECT_EQ(r.code, 4);
  EXPECT_NE(r.err.find("line 1: stdin holds the job list"), std::string::npos) << r.err;
}

// A job that reads what an earlier job writes waits for that write, whatever the overlap of their stages.
TEST_F(Batch, ALaterJobReadsWhatAnEarlierJobWrote) {
  write_inputs();
  write_jobs("jobs.txt", {q("dem.csv") + " -o " + q("tin.ply") + " --contours-out " + q("contours.wkt") +
                              " --interval 1",
                          q("contours.wkt") + " -o " + q("from-contours.ply"),
                          q("contours.wkt") + " " + q("grid.asc") + " -o " + q("both.obj")});
  Result r = run("batch " + q("jobs.txt"));
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(run("triangulate " + q("contours.wkt") + " -q -o " + q("single.ply")).code, 0);
  EXPECT_EQ(slurp(path("single.ply")), slurp(path("from-contours.ply")));
  ASSERT_EQ(run("triangulate " + q("contours.wkt") + " " + q("grid.asc") + " -q -o " + q("single.obj")).code, 0);
  EXPECT_EQ(slurp(path("single.obj")), slurp(path("both.obj")));
}

// samples/jobs.txt, the README's example, run from a folder that sees the repository's samples/: every job
// runs, and its first job's mesh is its single run's and passes verify.
TEST_F(Batch, TheBundledJobFileRuns) {
  const std::string samples = std::string(CDTGPU_SOURCE_DIR) + "/samples";
  fs::create_directory_symlink(samples, dir / "samples");
  const std::string in = "samples/katoomba/contours.shp:z=ELEV samples/katoomba/dem.xyz "
                         "samples/katoomba/buildings.shp:z=min";
  Result r = run("batch samples/jobs.txt");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("batch: 4 jobs, all ok"), std::string::npos) << r.err;
  ASSERT_EQ(run("triangulate " + in + " -q -o single.ply").code, 0);
  const Result v = run("verify katoomba.ply " + in);
  EXPECT_EQ(v.code, 0) << v.err;
  for (const char* out : {"katoomba.ply", "katoomba.json", "katoomba dem only.obj", "katoomba.xml",
                          "katoomba-dem.asc", "katoomba-contours.geojson", "katoomba holes.2dm"})
    EXPECT_TRUE(fs::exists(path(out))) << out;
  EXPECT_TRUE(slurp(path("katoomba.ply")) == slurp(path("single.ply")));
}

}  // namespace

// In a batch of kBatchWarmJobs jobs or more, auto counts the GPU's start-up once and wants the GPU from
// kBatchAutoMinPoints points (here it falls back to CGAL where the machine has no hardware GPU, and says so);
// a shorter batch and a single run keep the single run's rule. The bytes are the single run's either way.
// The jobs in flight stay within the machine's memory together: on a "machine" (CDTGPU_HOST_MEMORY) that holds
// one job's estimate but not two, each job waits for the one before it, and every job still writes its single
// run's bytes. With the real machine's memory none waits.
TEST_F(Batch, JobsInFlightStayWithinTheMachinesMemory) {
  const std::string s = std::string(CDTGPU_SOURCE_DIR) + "/samples/katoomba/";
  const std::string in = s + "dem.xyz '" + s + "contours.shp:z=ELEV' --backend cgal";
  ASSERT_EQ(run("triangulate " + in + " -q -o " + q("single.ply")).code, 0);
  std::vector<std::string> lines;
  for (int k = 0; k < 4; ++k) lines.push_back(in + " -o " + q(std::string("m").append(std::to_string(k)) + ".ply"));
  write_jobs("jobs.txt", lines);
  // About 7.5K points estimated from the files, at one CGAL run's 315 bytes each: 2.4 MB a job.
  setenv("CDTGPU_HOST_MEMORY", "3500000", 1);
  const Result tight = run("batch " + q("jobs.txt") + " -v");
  unsetenv("CDTGPU_HOST_MEMORY");
  ASSERT_EQ(tight.code, 0) << tight.err;
  EXPECT_NE(tight.err.find("waits for memory"), std::string::npos) << tight.err;
  for (int k = 2; k <= 4; ++k) {  // each job read only once the one before it is done
    const size_t read = tight.err.find("line " + std::to_string(k) + ": read:");
    const size_t before_done = tight.err.find("line " + std::to_string(k - 1) + ": ok");
    ASSERT_NE(read, std::string::npos) << tight.err;
    EXPECT_GT(read, before_done) << k << "\n" << tight.err;
  }
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(slurp(path("m" + std::to_string(k) + ".ply")) == slurp(path("single.ply"))) << k;
  const Result roomy = run("batch " + q("jobs.txt") + " -v");
  ASSERT_EQ(roomy.code, 0) << roomy.err;
  EXPECT_EQ(roomy.err.find("waits for memory"), std::string::npos) << roomy.err;
}

TEST_F(Batch, ManyJobsWantTheGpuForSmallerInputs) {
  using cdtgpu::kBatchWarmJobs;
  std::ostringstream xyz;
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 100; ++j)
      xyz << 500000 + i * 3 << '.' << (i * 7 + j * 3) % 10 << ' ' << 6000000 + j * 3 << '.' << (i + j * 9) % 10
          << ' ' << 100 + (i * j) % 17 << '\n';
  write("dem12k.xyz", xyz.str());  // 12000 points: more than kBatchAutoMinPoints, fewer than kAutoMinPoints
  ASSERT_EQ(run("triangulate " + q("dem12k.xyz") + " -q -o " + q("single.ply") + " --stats " + q("single.json"))
                .code,
            0);
  const std::string single_reason = stats("single.json")["backend_reason"];
  EXPECT_NE(single_reason.find("fewer than 100000"), std::string::npos) << single_reason;
  auto job = [](size_t k) {  // "b" + std::to_string(k), which GCC 12 warns about falsely (-Wrestrict)
    std::string name = "b";
    name += std::to_string(k);
    return name;
  };
  for (const size_t n : {kBatchWarmJobs - 1, kBatchWarmJobs}) {
    std::vector<std::string> lines;
    for (size_t k = 0; k < n; ++k)
      lines.push_back(q("dem12k.xyz") + " -o " + q(job(k) + ".ply") + " --stats " + q(job(k) + ".json"));
    write_jobs("jobs.txt", lines);
    Result r = run("batch " + q("jobs.txt"));
    ASSERT_EQ(r.code, 0) << r.err;
    for (size_t k = 0; k < n; ++k) {
      const std::string name = job(k);
      EXPECT_TRUE(slurp(path(name + ".ply")) == slurp(path("single.ply"))) << n << " " << name;
      const nlohmann::json s = stats(name + ".json");
      const std::string reason = s["backend_reason"];
      if (n < kBatchWarmJobs) {
        EXPECT_EQ(reason, single_reason);
      } else {
        EXPECT_EQ(reason.find("fewer than"), std::string::npos) << reason;
        EXPECT_TRUE(s["backend"] == "gpu" || reason.rfind("no GPU to use", 0) == 0) << reason;
      }
    }
  }
}

// Device workers (--devices): two on the one device there is (lavapipe in CI) take the GPU jobs as they come,
// each its own Vulkan device, and every job still writes its single run's bytes (two writers, any order); a
// job naming its own --device shares that device's start with a worker, one job at a time. A bad index, or
// --devices beside --device, is refused before any job runs.
TEST_F(Batch, DeviceWorkersGiveEachJobItsSingleRunsBytes) {
  write_inputs();
  const std::string terrain = q("dem.csv") + " " + q("lines.wkt");
  ASSERT_EQ(run("triangulate " + terrain + " --backend gpu -q -o " + q("single.ply")).code, 0);
  ASSERT_EQ(run("triangulate " + terrain + " --backend gpu -q --grid-out " + q("single.asc") +
                " --cell 2.5 -o " + q("single-grid.ply"))
                .code,
            0);
  std::vector<std::string> lines;
  for (int k = 0; k < 8; ++k) {
    const std::string n = std::to_string(k);
    if (k % 3 == 2)
      lines.push_back(terrain + " --backend gpu --grid-out " + q("g" + n + ".asc") + " --cell 2.5 -o " +
                      q("g" + n + ".ply") + (k == 5 ? " --device 0" : ""));
    else
      lines.push_back(terrain + " --backend gpu -o " + q("m" + n + ".ply"));
  }
  write_jobs("jobs.txt", lines);
  Result r = run("batch " + q("jobs.txt") + " --devices 0,0 -v");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("batch: 2 device workers: 1 on device 0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("device stages on worker 1 of 2"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("device stages on worker 2 of 2"), std::string::npos) << r.err;
  for (int k = 0; k < 8; ++k) {
    const std::string n = std::to_string(k);
    if (k % 3 == 2) {
      EXPECT_TRUE(slurp(path("g" + n + ".ply")) == slurp(path("single-grid.ply"))) << k;
      EXPECT_TRUE(slurp(path("g" + n + ".asc")) == slurp(path("single.asc"))) << k;
    } else {
      EXPECT_TRUE(slurp(path("m" + n + ".ply")) == slurp(path("single.ply"))) << k;
    }
    EXPECT_NE(r.err.find("line " + std::to_string(k + 1) + ": ok, "), std::string::npos) << k << "\n" << r.err;
  }
  // `all`: every hardware GPU, or the one device there is (lavapipe: one worker, no list of workers).
  Result all = run("batch " + q("jobs.txt") + " --devices all");
  ASSERT_EQ(all.code, 0) << all.err;
  EXPECT_TRUE(slurp(path("m0.ply")) == slurp(path("single.ply")));
  Result bad = run("batch " + q("jobs.txt") + " --devices 0,7");
  EXPECT_EQ(bad.code, 3) << bad.err;
  EXPECT_NE(bad.err.find("device index 7 out of range"), std::string::npos) << bad.err;
  Result both = run("--device 0 batch " + q("jobs.txt") + " --devices 0");
  EXPECT_EQ(both.code, 2) << both.err;
  EXPECT_NE(both.err.find("not both"), std::string::npos) << both.err;
}
