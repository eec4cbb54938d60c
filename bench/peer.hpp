// cdtgpu bench --table peer: the GPU stages beside gDel2D's (the CUDA peer) on identical inputs, built from the
// e2e workload and written in gDel2D's binary input format (bench/peer.cpp says how).
//
//   BenchOptions o;                        // bench/bench.hpp
//   o.table = "peer";
//   o.rows = {"2M+500K", "4M+1M"};         // points + constraint segments
//   o.peer = "/path/to/gdel2d";            // its GDelFlipping-style executable; empty: our columns only
//   int code = run_peer(o);                // 1 when a row's triangles differ from CGAL's
#pragma once
#include "bench/bench.hpp"

namespace cdtgpu {

int run_peer(const BenchOptions& options);

}  // namespace cdtgpu
