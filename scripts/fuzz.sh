#!/usr/bin/env bash
# Builds the reader fuzz targets (fuzz/, clang + libFuzzer + ASan + UBSan) in build-fuzz/ and runs each for
# SECONDS (default 60) from seed corpora made of tests/data and samples/. Crashes land in
# build-fuzz/artifacts/<target>/; add each to tests/data/fuzz/<target>/ (tests/fuzz_regression_test.cpp
# replays them). Usage: scripts/fuzz.sh [seconds] [target...]   (targets: wkt xyz ascii_grid mesh shapefile)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(wkt xyz ascii_grid mesh shapefile)
CXX=${CXX:-clang++-14}
jobs=${JOBS:-2}

cmake -S . -B build-fuzz -DCDTGPU_FUZZ=ON -DCMAKE_CXX_COMPILER="$CXX" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build-fuzz -j"$jobs" --target "${targets[@]/#/fuzz_}"

seeds=build-fuzz/seeds
rm -rf "$seeds"
mkdir -p "$seeds"/{wkt,xyz,ascii_grid,mesh,shapefile}
cp tests/data/readers/*.wkt "$seeds"/wkt/
cp tests/data/readers/*.csv "$seeds"/xyz/
head -c 4000 samples/katoomba/dem.xyz >"$seeds"/xyz/dem_head.xyz
cp tests/data/readers/*.asc "$seeds"/ascii_grid/
# Mesh seeds: a small mesh in each format, first byte 0/1/2 = obj/ply/wkt (fuzz/harness.hpp).
printf '\000# crs: none\nv 0 0 1\nv 1 0 2\nv 0 1 3\nf 1 2 3\n' >"$seeds"/mesh/tri.obj
printf '\001ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n0 0 1\n1 0 2\n0 1 3\n3 0 1 2\n' >"$seeds"/mesh/tri.ply
printf '\002TIN Z (((0 0 1, 1 0 2, 0 1 3, 0 0 1)))\n' >"$seeds"/mesh/tri.wkt
# Shapefile seeds: [flags][shp length u32 le][shx length u32 le] shp shx dbf, from the sample.
python3 - "$seeds"/shapefile <<'PY'
import struct, sys
out = sys.argv[1]
for name, flags in (("buildings", 0), ("buildings", 4), ("contours", 1)):
    base = "samples/katoomba/" + name
    shp, shx, dbf = (open(base + e, "rb").read() for e in (".shp", ".shx", ".dbf"))
    if name == "contours":  # keep the seed small: the first three records, headers patched
        n = 3
        end = struct.unpack(">i", shx[100 + 8 * (n - 1):104 + 8 * (n - 1)])[0] * 2 + 8 + \
            struct.unpack(">i", shx[104 + 8 * (n - 1):108 + 8 * (n - 1)])[0] * 2
        shp = shp[:24] + struct.pack(">i", end // 2) + shp[28:end]
        shx = shx[:24] + struct.pack(">i", (100 + 8 * n) // 2) + shx[28:100 + 8 * n]
    with open(f"{out}/{name}_{flags}.bin", "wb") as f:
        f.write(bytes([flags]) + struct.pack("<II", len(shp), len(shx)) + shp + shx + dbf)
PY

status=0
for t in "${targets[@]}"; do
  mkdir -p build-fuzz/corpus/"$t" build-fuzz/artifacts/"$t"
  echo "== fuzz_$t for ${seconds}s"
  build-fuzz/fuzz_"$t" build-fuzz/corpus/"$t" "$seeds"/"$t" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix=build-fuzz/artifacts/"$t"/ 2>build-fuzz/fuzz_"$t".log || status=1
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|cov:" build-fuzz/fuzz_"$t".log | tail -3
done
ls build-fuzz/artifacts/*/ 2>/dev/null || true
exit $status
