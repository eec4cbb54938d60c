// The constraint resolve (core/resolve.hpp) on the tiles bench's workload at growing sizes (Google Benchmark):
// n uniform points and their band chains (n / 4 segments), prepared once; resolve_constraints timed. Its cost
// a vertex should not grow with n; at 1B points on 32 cores it took ~6 s, 3x what 2M on 2 cores predicts.
//
//   build/cdtgpu-resolve-bench [--sizes 2M,16M,64M] [--threads 1,2] [-v] [Google Benchmark flags]
// -v prints the resolve's own stage times (setup, round 1) on stderr.
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/prepare.hpp"
#include "core/resolve.hpp"
#include "core/workloads.hpp"

namespace {

const cdtgpu::PreparedInput& input(uint64_t n) {
  static std::map<uint64_t, std::unique_ptr<cdtgpu::PreparedInput>> made;
  std::unique_ptr<cdtgpu::PreparedInput>& p = made[n];
  if (!p) {
    cdtgpu::InputSet in = cdtgpu::uniform_points(n, 1);
    cdtgpu::add_band_chains(in);
    p = std::make_unique<cdtgpu::PreparedInput>(cdtgpu::prepare(in));
  }
  return *p;
}

void resolve(benchmark::State& state) {
  const cdtgpu::PreparedInput& p = input(uint64_t(state.range(0)));
  for (auto _ : state) {
    cdtgpu::ResolvedInput r = cdtgpu::resolve_if_needed(p, unsigned(state.range(1)));
    benchmark::DoNotOptimize(r.unchanged);
  }
  state.counters["ns/vertex/thread"] = benchmark::Counter(
      double(state.iterations()) * double(p.vertices.size()) / double(state.range(1)),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

// "2M,16M" or "1,2": numbers with an optional K, M or G.
std::vector<int64_t> numbers(const char* list) {
  std::vector<int64_t> out;
  for (const char* p = list; *p;) {
    char* end = nullptr;
    double v = std::strtod(p, &end);
    if (end == p) throw std::invalid_argument(std::string("not a number list: ") + list);
    if (*end == 'K') v *= 1e3, ++end;
    if (*end == 'M') v *= 1e6, ++end;
    if (*end == 'G') v *= 1e9, ++end;
    out.push_back(int64_t(v));
    p = *end == ',' ? end + 1 : end;
  }
  return out;
}

int main(int argc, char** argv) {
  std::vector<int64_t> sizes{2'000'000, 16'000'000, 64'000'000}, threads{1, 2};
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--sizes") && i + 1 < argc) sizes = numbers(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = numbers(argv[++i]);
    else if (!std::strcmp(argv[i], "-v")) spdlog::set_level(spdlog::level::debug);
    else rest.push_back(argv[i]);
  }
  benchmark::RegisterBenchmark("resolve", resolve)
      ->ArgsProduct({sizes, threads})
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  int n = int(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
