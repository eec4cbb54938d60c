#!/usr/bin/env bash
# The bench as docs/performance.md reports it, on the lent GPU machine: build here, pack with
#   ../shared/tools/devpack build/cdtgpu
# then run one part per device call (each fits the 10-minute limit), carrying .devpack:
#   bash scripts/device-bench.sh 1    # tables 1 and 2, the ablation
#   bash scripts/device-bench.sh 2    # Delaunay only, long constraints, terrain
#   bash scripts/device-bench.sh 3    # end to end (cdtgpu triangulate as a child): 20K, 200K, 2M points
#   bash scripts/device-bench.sh 4    # end to end: 4M points
# JSON files and nvidia-smi's clock log go to $OUT (the device tool's folder), else ./bench-out. Plot them with
#   scripts/plot_bench.py OUT/*.json -o docs/img
set -euo pipefail
part=${1:?usage: device-bench.sh 1|2|3|4}
out=${OUT:-bench-out}
mkdir -p "$out"
run() { bash .devpack/run cdtgpu "$@"; }
nvidia-smi --query-gpu=timestamp,clocks.sm,clocks.mem,utilization.gpu,power.draw --format=csv,noheader \
  -lms 250 >"$out/smi-part$part.csv" 2>&1 &
smi=$!
trap 'kill $smi 2>/dev/null || true' EXIT
common=(--runs 7 --cgal-runs 1)
case $part in
  1)
    run bench --table 1 "${common[@]}" --json "$out/h100-t1.json"
    run bench --table 2 "${common[@]}" --json "$out/h100-t2.json"
    run bench --ablation "${common[@]}" --json "$out/h100-ablation.json"
    ;;
  2)
    run bench --table dt "${common[@]}" --json "$out/h100-dt.json"
    run bench --table long "${common[@]}" --json "$out/h100-long.json"
    run bench --table terrain "${common[@]}" --json "$out/h100-terrain.json"
    ;;
  3)
    run bench --table e2e --sizes 20K,200K,2M --json "$out/h100-e2e-small.json"
    ;;
  4)
    run bench --table e2e --sizes 4M --json "$out/h100-e2e-4m.json"
    ;;
  *) echo "part must be 1, 2, 3 or 4" >&2; exit 2 ;;
esac
