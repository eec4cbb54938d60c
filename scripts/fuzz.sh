#!/usr/bin/env bash
# Builds the reader fuzz targets (fuzz/, clang + libFuzzer + ASan + UBSan) in $FUZZ_DIR (default build-fuzz/) and
# runs each for SECONDS (default 60) from seed corpora made of tests/data and samples/. Crashes land in
# $FUZZ_DIR/artifacts/<target>/; add each to tests/data/fuzz/<target>/ (tests/fuzz_regression_test.cpp replays
# them). Prints per target: executions, coverage (cov, ft) and crash files; exits 1 when any target crashed.
#   scripts/fuzz.sh [seconds] [target...]      targets: wkt xyz ascii_grid mesh shapefile geotiff geojson las (default all)
# Environment: JOBS (build jobs, default 2); FORK=N (N worker processes per target, libFuzzer -fork);
# RUNS=N (stop each target after N executions instead of the time); FUZZ_BIN=dir (fuzz_* binaries built
# elsewhere, e.g. packed for a many-core machine without a compiler: no build here).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(wkt xyz ascii_grid mesh shapefile geotiff geojson las)
CXX=${CXX:-clang++-14}
jobs=${JOBS:-2}
dir=${FUZZ_DIR:-build-fuzz}
bin=${FUZZ_BIN:-$dir}

if [ -z "${FUZZ_BIN:-}" ]; then
  cmake -S . -B "$dir" -DCDTGPU_FUZZ=ON -DCMAKE_CXX_COMPILER="$CXX" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
  cmake --build "$dir" -j"$jobs" --target "${targets[@]/#/fuzz_}"
fi
mkdir -p "$dir"

seeds=$dir/seeds
rm -rf "$seeds"
mkdir -p "$seeds"/{wkt,xyz,ascii_grid,mesh,shapefile,geotiff,geojson,las}
cp tests/data/readers/*.wkt "$seeds"/wkt/
cp tests/data/readers/*.csv "$seeds"/xyz/
head -c 4000 samples/katoomba/dem.xyz >"$seeds"/xyz/dem_head.xyz
cp tests/data/readers/*.asc "$seeds"/ascii_grid/
cp tests/data/readers/*.tif "$seeds"/geotiff/
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

# GeoJSON seeds: [flags] text (fuzz/harness.hpp; flag 1: z from the property "z").
for f in tests/data/readers/*.geojson; do
  { printf '\001'; cat "$f"; } >"$seeds"/geojson/"$(basename "$f")"
done
# LAS seeds: [flags] file, written here from the LAS specification (as tests/las_writer.hpp does): 1.2 format 1,
# 1.4 format 6 with a WKT VLR and a GeoKeys EVLR, 1.4 format 3 with extra bytes.
python3 - "$seeds"/las <<'PY'
import struct, sys
out = sys.argv[1]
sizes = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]
def las(minor, fmt, extra=0, vlrs=(), evlrs=(), n=6):
    hsize = {2: 227, 3: 235, 4: 375}[minor]
    vbytes = b"".join(struct.pack("<H16sHH32s", 0, u, i, len(d), b"seed") + d for u, i, d in vlrs)
    rec = sizes[fmt] + extra
    pts = b""
    for k in range(n):
        r = bytearray(rec)
        struct.pack_into("<iiiH", r, 0, 1000 * k, 2000 - 300 * k, 50 * k, 100)
        if fmt < 6:
            r[14] = 1 | (1 + k % 2) << 3
            r[15] = (2 if k % 2 else 1) | (0x80 if k == 3 else 0)
        else:
            r[14] = 1 | (1 + k % 2) << 4
            r[15] = 0x04 if k == 3 else 0
            r[16] = 2 if k % 2 else 40
        pts += bytes(r)
    off = hsize + len(vbytes)
    h = bytearray(hsize)
    struct.pack_into("<4sHH", h, 0, b"LASF", 0, 0x11 if fmt >= 6 else 1)
    h[24], h[25] = 1, minor
    struct.pack_into("<HIIBHI", h, 94, hsize, off, len(vlrs), fmt, rec, 0 if fmt >= 6 else n)
    struct.pack_into("<6d", h, 131, 0.01, 0.01, 0.01, 334000, 6250000, 0)
    ebytes = b"".join(struct.pack("<H16sHQ32s", 0, u, i, len(d), b"seed") + d for u, i, d in evlrs)
    if minor >= 4:
        struct.pack_into("<QQIQ", h, 227, 0, off + len(pts) if evlrs else 0, len(evlrs), n)
    return bytes(h) + vbytes + pts + ebytes
wkt = b'PROJCS["GDA2020 / MGA zone 56"]\0'
keys = struct.pack("<12H", 1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 7856)
seeds = {"v12_f1.bin": (0, las(2, 1)),
         "v14_f6_crs.bin": (8, las(4, 6, vlrs=[(b"LASF_Projection", 2112, wkt)], evlrs=[(b"LASF_Projection", 34735, keys)])),
         "v14_f3_extra.bin": (5, las(4, 3, extra=4))}
for name, (flags, data) in seeds.items():
    open(f"{out}/{name}", "wb").write(bytes([flags]) + data)
PY

status=0
limit=(-max_total_time="$seconds")
[ -n "${RUNS:-}" ] && limit=(-runs="$RUNS")
fork=()
[ -n "${FORK:-}" ] && fork=(-fork="$FORK" -ignore_crashes=1)
for t in "${targets[@]}"; do
  # Crash files of earlier runs are gone: each run reports its own (those worth keeping are in tests/data/fuzz).
  rm -rf "$dir"/artifacts/"$t"
  mkdir -p "$dir"/corpus/"$t" "$dir"/artifacts/"$t"
  echo "== fuzz_$t: ${RUNS:+$RUNS executions}${RUNS:-${seconds}s}${FORK:+, $FORK workers}"
  start=$(date +%s)
  "$bin"/fuzz_"$t" "$dir"/corpus/"$t" "$seeds"/"$t" "${limit[@]}" "${fork[@]}" -timeout=10 -rss_limit_mb=2048 \
    -malloc_limit_mb=1024 -max_len=65536 -print_final_stats=1 -artifact_prefix="$dir"/artifacts/"$t"/ \
    >"$dir"/fuzz_"$t".log 2>&1 || status=1
  # The last status line ("#N ... cov: C ft: F ...") holds the totals, in fork mode too.
  last=$(grep -E '^#[0-9]+' "$dir"/fuzz_"$t".log | tail -1 || true)
  crashes=$(find "$dir"/artifacts/"$t" -type f | wc -l)
  runs=$(echo "$last" | grep -oE '^#[0-9]+' | tr -d '#' || true)
  echo "   $(( $(date +%s) - start ))s, executions ${runs:-?}, $(echo "$last" | grep -oE 'cov: [0-9]+ ft: [0-9]+' || true), crash files: $crashes"
  [ "$crashes" -eq 0 ] || status=1
done
exit $status
