// A GPU tile's final triangles out of the staging buffer and into the whole's ids (Google Benchmark): copied,
// then mapped through the tile's ids (the two passes before session 44), against mapped as they are copied
// (gpu::GpuCdt::unstage_triangles with ids). 250M triangles is a tile of the 1B bench (134M points).
//
//   build/cdtgpu-copy-out-bench --benchmark_filter=250000000
#include <benchmark/benchmark.h>
#include <tbb/parallel_for.h>

#include <numeric>
#include <vector>

#include "gpu/cdt_pipeline.hpp"

namespace {

using cdtgpu::Triangle;
using cdtgpu::gpu::GpuCdt;

struct Tile {
  std::vector<uint32_t> ids;  // sorted, as a tile's are
  std::vector<Triangle> staged;
  explicit Tile(size_t triangles) : ids(triangles / 2), staged(triangles) {
    std::iota(ids.begin(), ids.end(), 7u);
    const uint32_t n = uint32_t(ids.size());
    // Neighbouring vertices, as a canonical list of a tile's triangles has them (a slab of 125M points: a
    // vertex's neighbours ~11K ids away).
    tbb::parallel_for(size_t(0), triangles, [&](size_t i) {
      const uint32_t a = uint32_t(i / 2 % n);
      staged[i] = {a, (a + 1) % n, (a + 11180) % n};
    });
  }
};

// The staging buffer's mapped memory, lent (not unmapped at the end).
struct Lent {
  cdtgpu::gpu::HostStaging staging;
  explicit Lent(void* memory) { staging.mapped = memory; }
  ~Lent() { staging.mapped = nullptr; }
};

void copy_then_map(benchmark::State& state) {
  const Tile tile(size_t(state.range(0)));
  Lent lent(const_cast<Triangle*>(tile.staged.data()));
  for (auto _ : state) {
    cdtgpu::TileFinal f;
    GpuCdt::unstage_triangles(lent.staging, uint32_t(tile.staged.size()), f);
    tbb::parallel_for(size_t(0), f.triangles.size(), [&](size_t i) {
      for (uint32_t& v : f.triangles[i]) v = tile.ids[v];
    });
    benchmark::DoNotOptimize(f.triangles.data());
  }
}

void mapped_in_the_copy(benchmark::State& state) {
  const Tile tile(size_t(state.range(0)));
  Lent lent(const_cast<Triangle*>(tile.staged.data()));
  for (auto _ : state) {
    cdtgpu::TileFinal f;
    GpuCdt::unstage_triangles(lent.staging, uint32_t(tile.staged.size()), tile.ids, f);
    benchmark::DoNotOptimize(f.triangles.data());
  }
}

BENCHMARK(copy_then_map)->Arg(25'000'000)->Arg(250'000'000)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(mapped_in_the_copy)->Arg(25'000'000)->Arg(250'000'000)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
