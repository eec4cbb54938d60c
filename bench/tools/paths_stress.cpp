// Every path of cdtgpu triangulate on degenerate lattice inputs (tests/tile_layouts.hpp lattice_soup): the CPU's
// one-piece run (the reference), its tiles, the GPU's single run and its tiles as the CLI runs them (unresolved
// first, resolved if a tile finds a crossing). Prints each input that any path fails or meshes otherwise; exit
// 1 if one did. The test suite runs 16 small ones on lavapipe; this runs many and large ones on a real GPU.
//
//   build/cdtgpu-paths-stress FROM TO [SCALE] [--cpu-only]
// SCALE multiplies the points (50-1200) and lines (0-40) of each input.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstring>
#include <optional>
#include <string>

#include "core/cdt_cgal.hpp"
#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/tiles.hpp"
#include "core/tiles_ahead.hpp"
#include "gpu/cdt_pipeline.hpp"
#include "gpu/tile_triangulator.hpp"
#include "tests/tile_layouts.hpp"

using namespace cdtgpu;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s FROM TO [SCALE] [--cpu-only]\n", argv[0]);
    return 2;
  }
  const uint64_t from = std::stoull(argv[1]), to = std::stoull(argv[2]);
  const int scale = argc > 3 && argv[3][0] != '-' ? std::stoi(argv[3]) : 1;
  const bool gpu = std::strcmp(argv[argc - 1], "--cpu-only") != 0;
  spdlog::set_level(spdlog::level::warn);
  std::optional<gpu::Context> ctx;
  std::optional<gpu::GpuCdt> cdt;
  if (gpu) {
    ctx.emplace(gpu::create_context(gpu::ContextOptions{}));
    cdt.emplace(*ctx);
    std::printf("device: %s\n", ctx->info.name.c_str());
  }
  int bad = 0, crossing = 0;
  for (uint64_t seed = from; seed <= to; ++seed) {
    const PreparedInput p = prepare(tile_layouts::lattice_soup(seed, scale));
    auto fail = [&](const std::string& what) {
      ++bad;
      std::printf("soup %lu (%zu vertices, %zu constraints): %s\n", seed, p.vertices.size(), p.constraints.size(),
                  what.c_str());
      std::fflush(stdout);
    };
    CdtResult single;
    try {
      single = triangulate_cgal(p);
    } catch (const std::exception& e) {
      fail(std::string("the CPU's run threw: ") + e.what());
      continue;
    }
    crossing += single.steiner_points > 0;
    auto check = [&](const std::string& what, auto&& run) {
      try {
        const CdtResult r = run();
        if (r.mesh.vertices != single.mesh.vertices || r.mesh.triangles != single.mesh.triangles)
          fail(what + ": another mesh (" + std::to_string(r.mesh.triangles.size()) + " triangles against " +
               std::to_string(single.mesh.triangles.size()) + ")");
      } catch (const std::exception& e) {
        fail(what + " threw: " + e.what());
      }
    };
    const uint64_t n = p.vertices.size();
    for (const uint64_t tp : {uint64_t(64), n / 3 + 3}) {
      TileOptions opt;
      opt.max_tile_points = tp;
      check("CPU tiles of " + std::to_string(tp),
            [&] { return triangulate_tiled(resolve_constraints(p), opt, cgal_tile_triangulator()); });
    }
    if (!gpu) continue;
    check("GPU", [&] { return cdt->triangulate(p); });
    for (const uint64_t tp : {std::max<uint64_t>(200, n / 16), n / 3 + 3}) {
      check("GPU tiles of " + std::to_string(tp), [&] {
        const gpu::GpuTiles tiles = gpu::gpu_tiles({&*cdt});
        TileOptions opt;
        opt.max_tile_points = tp;
        opt.tiles_in_flight = 2;
        opt.finalize = tiles.finalize;
        opt.reserve = tiles.reserve;
        return triangulate_tiled_checking(p, opt, tiles.triangulate);
      });
    }
  }
  std::printf("soups %lu..%lu at scale %d: %d failed, %d with crossings\n", from, to, scale, bad, crossing);
  return bad ? 1 : 0;
}
