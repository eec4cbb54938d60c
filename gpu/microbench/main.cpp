// cdtgpu_microbench: throughput of the GPU primitives, timed with GPU timestamps. After two warm-up runs,
// prints the median of N runs (default 11) of: exclusive scan (16M, 64M uint32), radix sort (16M keys of
// 32 and 64 bits with a uint32 payload), and 4M predicate quadruples when shaders/predicates_eval.comp
// exists; then host costs (buffer allocation, submit round trip, staging transfers) on the host clock. Sizes
// over the device's maxStorageBufferRange are skipped with a note.
//
//   cdtgpu_microbench [--device NAME|INDEX] [--runs N] [--scale F] [--chain]
//   (--scale 0.05: small sizes for lavapipe; --chain: only the chain of tiny commands)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "gpu/buffers.hpp"
#include "gpu/check.hpp"
#include "gpu/context.hpp"
#include "gpu/passes.hpp"
#include "gpu/primitives.hpp"
#include "gpu/profiler.hpp"
#include "gpu/recorder.hpp"
#include "shaders/layout.h"

using namespace cdtgpu::gpu;

namespace {

struct Options {
  std::string device;
  int runs = 11;
  double scale = 1.0;
  bool chain_only = false;
};

// Median GPU time of `runs` recordings: `setup` records untimed work (e.g. restoring the input), `work` the
// timed stage.
double median_ms(const Context& ctx, int runs, const std::function<void(Recorder&)>& setup,
                 const std::function<void(Recorder&)>& work) {
  std::vector<double> ms;
  Recorder rec(ctx);
  Profiler prof(ctx, 4);
  for (int i = 0; i < runs + 2; ++i) {
    prof.reset();
    setup(rec);
    prof.begin(rec, "work");
    work(rec);
    prof.end(rec);
    rec.submit();
    if (i >= 2) ms.push_back(prof.results()[0].ms);  // the first two are warm-up
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

void report(const char* what, uint64_t n, double ms) {
  std::printf("%-34s n=%11llu  median %9.3f ms  %8.3f G elements/s\n", what, static_cast<unsigned long long>(n), ms,
              static_cast<double>(n) / (ms * 1e-3) * 1e-9);
}

bool fits(const Context& ctx, uint64_t bytes, const char* what, uint64_t n) {
  if (bytes <= ctx.info.max_storage_buffer_range) return true;
  std::printf("%-34s n=%11llu  skipped: %llu bytes > maxStorageBufferRange %llu\n", what,
              static_cast<unsigned long long>(n), static_cast<unsigned long long>(bytes),
              static_cast<unsigned long long>(ctx.info.max_storage_buffer_range));
  return false;
}

void bench_scan(const Context& ctx, const Primitives& prims, const Options& o, uint64_t n) {
  if (!fits(ctx, n * 4, "exclusive scan u32", n)) return;
  std::vector<uint32_t> v(n);
  std::mt19937 rng(1);
  for (auto& x : v) x = rng() & 15;
  Buffer in = upload_new(ctx, v, "in");
  Buffer out = create_buffer(ctx, n * 4, "out");
  double ms = median_ms(ctx, o.runs, [](Recorder&) {},
                        [&](Recorder& rec) { prims.exclusive_scan(rec, in, out, uint32_t(n)); });
  report("exclusive scan u32", n, ms);
}

void bench_sort(const Context& ctx, const Primitives& prims, const Options& o, uint64_t n, uint32_t key_bits) {
  const char* what = key_bits == 32 ? "radix sort u32 key + u32 payload" : "radix sort u64 key + u32 payload";
  uint64_t key_bytes = n * key_bits / 8;
  if (!fits(ctx, key_bytes, what, n)) return;
  std::mt19937_64 rng(2);
  std::vector<uint32_t> words(key_bytes / 4);
  for (auto& w : words) w = static_cast<uint32_t>(rng());
  std::vector<uint32_t> payload(n);
  std::iota(payload.begin(), payload.end(), 0u);
  Buffer keys0 = upload_new(ctx, words, "keys0");
  Buffer keys = create_buffer(ctx, key_bytes, "keys");
  Buffer pay0 = upload_new(ctx, payload, "payload0");
  Buffer pay = create_buffer(ctx, n * 4, "payload");
  double ms = median_ms(
      ctx, o.runs,
      [&](Recorder& rec) {
        rec.copy(keys0, keys, key_bytes);
        rec.copy(pay0, pay, n * 4);
      },
      [&](Recorder& rec) { prims.radix_sort(rec, keys, pay, uint32_t(n), key_bits); });
  report(what, n, ms);
}

// Predicate throughput: shaders/predicates_eval.comp (bindings: 0 = dvec2 quadruples, 1 = int signs, three per
// quadruple: orient2d, incircle, perturbed incircle; count = quads.length() / 4; workgroup 64, no push block).
// Two inputs: random points (the float filter decides) and co-circular grid cells (every incircle exact and 0).
void bench_predicates(const Context& ctx, const Options& o, uint64_t n) {
  auto names = shader_names();
  if (std::find(names.begin(), names.end(), "predicates_eval") == names.end()) {
    std::printf("predicates                         skipped: shaders/predicates_eval.comp not built in\n");
    return;
  }
  if (!fits(ctx, n * 64, "predicates (3 per quadruple)", n)) return;
  Pass eval = create_pass(ctx, {"predicates_eval", 2, 0});
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coord(-1000.0, 1000.0);
  for (int grid = 0; grid < 2; ++grid) {
    std::vector<double> xy(n * 8);
    for (uint64_t i = 0; i < n; ++i) {
      double* q = &xy[8 * i];
      if (grid) {  // corners of a unit grid cell far from the origin: co-circular, the exact path decides
        double x = 500000.0 + double(rng() % 1000), y = 6000000.0 + double(rng() % 1000);
        double c[8] = {x, y, x + 1, y, x + 1, y + 1, x, y + 1};
        std::copy(c, c + 8, q);
      } else {
        for (int k = 0; k < 8; ++k) q[k] = coord(rng);
      }
    }
    Buffer quads = upload_new(ctx, xy, "quads");
    Buffer signs = create_buffer(ctx, n * 12, "signs");
    double ms = median_ms(ctx, o.runs, [](Recorder&) {},
                          [&](Recorder& rec) { rec.dispatch_groups_raw(eval, {quads, signs}, nullptr, (n + 63) / 64); });
    report(grid ? "predicates x3, co-circular grid" : "predicates x3, random points", n, ms);
  }
}

// What a chain of tiny dependent commands costs on the GPU clock (each with the recorder's full barrier
// before it): the DT build's early rounds are such chains. 256 one-workgroup dispatches, 256 indirect
// dispatches of zero workgroups, 256 fills of one word.
void bench_chain(const Context& ctx, const Primitives& prims, const Options& o) {
  const int k = 256;
  Buffer data = create_buffer(ctx, 4096, "chain data");
  Buffer sums = create_buffer(ctx, 256, "chain sums");
  const uint32_t zero[3] = {0, 1, 1};
  Buffer args = upload_new(ctx, std::vector<uint32_t>(zero, zero + 3), "chain args");
  const layout::ScanAddPush push{128};
  double one = median_ms(
      ctx, o.runs, [](Recorder&) {},
      [&](Recorder& rec) {
        for (int i = 0; i < k; ++i) rec.dispatch(prims.scan_add, {data, sums}, push, 1);
      });
  double none = median_ms(
      ctx, o.runs, [](Recorder&) {},
      [&](Recorder& rec) {
        for (int i = 0; i < k; ++i) rec.dispatch_indirect(prims.scan_add, {data, sums}, &push, args);
      });
  double fills = median_ms(
      ctx, o.runs, [](Recorder&) {},
      [&](Recorder& rec) {
        for (int i = 0; i < k; ++i) rec.fill(sums, 0);
      });
  std::printf("chain of %d: one-group dispatch %.2f us, empty indirect %.2f us, fill %.2f us each\n", k,
              one * 1e3 / k, none * 1e3 / k, fills * 1e3 / k);
}

// Host costs the pipeline pays on every call, on the host clock: a device-local buffer allocated, filled once
// and freed, against the same fill on a kept buffer (their difference is the allocation); one submit + wait of
// a tiny command buffer (each host round trip between GPU stages costs this); an upload and a download of 64 MiB
// through the staging buffer.
void bench_host(const Context& ctx, const Options& o) {
  using Clock = std::chrono::steady_clock;
  auto median_host_ms = [&](const std::function<void()>& body) {
    std::vector<double> ms;
    for (int i = 0; i < o.runs + 2; ++i) {
      auto t0 = Clock::now();
      body();
      if (i >= 2) ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    return ms[ms.size() / 2];
  };
  for (uint64_t mib : {16, 64, 256}) {
    const uint64_t bytes = std::max<uint64_t>(4, uint64_t(double(mib << 20) * o.scale) & ~uint64_t(3));
    if (!fits(ctx, bytes, "host: allocate", bytes)) continue;
    Buffer kept = create_buffer(ctx, bytes, "kept");
    double fresh = median_host_ms([&] {
      Buffer b = create_buffer(ctx, bytes, "fresh");
      fill(ctx, b, 0);
    });
    double reuse = median_host_ms([&] { fill(ctx, kept, 0); });
    std::printf("host: allocate+fill+free %10llu B  median %9.3f ms  (fill of a kept buffer %.3f ms)\n",
                static_cast<unsigned long long>(bytes), fresh, reuse);
  }
  Buffer word = create_buffer(ctx, 4, "word");
  double trip = median_host_ms([&] {
    Recorder rec(ctx);
    rec.fill(word, 0);
    rec.submit();
  });
  std::printf("host: one submit + wait (tiny fill)           median %9.3f ms\n", trip);
  const uint64_t bytes = std::max<uint64_t>(4, uint64_t(double(64u << 20) * o.scale) & ~uint64_t(3));
  if (!fits(ctx, bytes, "host: transfers", bytes)) return;
  Buffer big = create_buffer(ctx, bytes, "transfer");
  std::vector<uint8_t> host(bytes, 1);
  double up = median_host_ms([&] { upload(ctx, big, host.data(), bytes); });
  double down = median_host_ms([&] { download(ctx, big, host.data(), bytes); });
  std::printf("host: upload / download %10llu B  median %9.3f / %.3f ms (%.1f / %.1f GB/s)\n",
              static_cast<unsigned long long>(bytes), up, down, bytes / up * 1e-6, bytes / down * 1e-6);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--device" && i + 1 < argc) o.device = argv[++i];
    else if (a == "--runs" && i + 1 < argc) o.runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--scale" && i + 1 < argc) o.scale = std::atof(argv[++i]);
    else if (a == "--chain")
      o.chain_only = true;
    else {
      std::fprintf(stderr,
                   "usage: cdtgpu_microbench [--device NAME|INDEX] [--runs N] [--scale F] [--chain]\n");
      return 2;
    }
  }
  try {
    ContextOptions co;
    co.device = o.device;
    Context ctx = create_context(co);
    std::printf("device: %s (%s, driver %s %s), subgroup %u, %d runs after 2 warm-up\n", ctx.info.name.c_str(),
                ctx.info.type.c_str(), ctx.info.driver_name.c_str(), ctx.info.driver_info.c_str(),
                ctx.info.subgroup_size, o.runs);
    Primitives prims(ctx);
    auto size = [&](uint64_t n) { return std::max<uint64_t>(1, static_cast<uint64_t>(n * o.scale)); };
    bench_chain(ctx, prims, o);
    if (o.chain_only) return 0;
    bench_scan(ctx, prims, o, size(16u << 20));
    bench_scan(ctx, prims, o, size(64u << 20));
    bench_sort(ctx, prims, o, size(16u << 20), 32);
    bench_sort(ctx, prims, o, size(16u << 20), 64);
    bench_predicates(ctx, o, size(4u << 20));
    bench_host(ctx, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cdtgpu_microbench: %s\n", e.what());
    return 3;
  }
  return 0;
}
