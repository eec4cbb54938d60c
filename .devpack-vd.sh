#!/usr/bin/env bash
# Voronoi vs default first stage on the lent GPU: DT bench per workload, then bench table 1 and the ablation.
cd "$(dirname "$0")/.."
export CDTGPU_VALIDATION=0 CDTGPU_DT_BENCH=7
for w in "1000000 u" "2000000 u" "4000000 u" "2000000 g" "2000000 c"; do
  set -- $w
  extra=""; [ "$2" = g ] && extra="CDTGPU_DT_BENCH_GRID=1"; [ "$2" = c ] && extra="CDTGPU_DT_BENCH_CLUSTERED=1"
  for s in insertion voronoi; do
    echo "=== $1 $2 $s"
    env $extra CDTGPU_DT_BENCH_POINTS=$1 CDTGPU_DT_START=$s bash .devpack/run gpu_delaunay_test --gtest_filter='*Bench*' 2>&1 | grep -E "dt bench|FAIL|rror"
  done
done
