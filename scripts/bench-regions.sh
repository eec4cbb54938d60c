#!/usr/bin/env bash
# Issue 28's regions rows: the e2e workload (uniform points + contour-like lines, text in, PLY out) triangulated
# plain, with a boundary ring and a hole ring (both crossing contours), with --max-edge 20, and with both; each
# mode run N times, median wall of the whole process and of the regions stage (--stats). The four meshes' bytes
# are checked against a second run of the same mode. On the lent GPU machine (after ../shared/tools/devpack):
#   bash scripts/bench-regions.sh 2M 7 [extra triangulate options...]
set -euo pipefail
size=${1:-2M}
runs=${2:-7}
shift $(( $# < 2 ? $# : 2 ))
out=${OUT:-bench-out}
mkdir -p "$out"
bin=${CDTGPU_BIN:-cdtgpu}  # another packed binary: CDTGPU_BIN=cdtgpu-base
if [ -f .devpack/run ]; then cdt() { bash .devpack/run "$bin" "$@"; }; else cdt() { "build/$bin" "$@"; }; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cdt bench --table e2e --sizes "$size" --backends cgal --formats text --keep "$work/e2e" -q >/dev/null 2>&1 || true
dir=$(dirname "$(find "$work/e2e" -name points.xyz | head -1)")
[ -f "$dir/contours.wkt" ] || { echo "no e2e input in $work/e2e" >&2; exit 1; }
# The e2e square is x in [500000, 510000), y in [6000000, 6010000): a 720-gon boundary of radius 4900 m and a
# 360-gon hole of radius 1500 m, both centred off the middle so their vertices fall between points.
ring() {  # cx cy r n
  awk -v cx="$1" -v cy="$2" -v r="$3" -v n="$4" 'BEGIN { printf "POLYGON (("; pi = atan2(0, -1);
    for (k = 0; k <= n; k++) { a = 2 * pi * (k % n) / n + 0.0123; printf "%s%.3f %.3f", (k ? ", " : ""), cx + r * cos(a), cy + r * sin(a) }
    print "))" }'
}
ring 505000.5 6005000.25 4900 720 >"$dir/boundary.wkt"
ring 504100.75 6005300.5 1500 360 >"$dir/hole.wkt"
inputs=("$dir/points.xyz" "$dir/contours.wkt")
regions=("$dir/boundary.wkt:role=boundary" "$dir/hole.wkt:role=hole")
median() { sort -n | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
stage() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['stage_ms'].get(sys.argv[2], 0))" "$1" "$2"; }
printf '%-18s %10s %10s %12s %12s\n' mode wall_ms regions_ms triangles same_bytes
for mode in plain regions max-edge both; do
  case $mode in
    plain) args=("${inputs[@]}") ;;
    regions) args=("${inputs[@]}" "${regions[@]}") ;;
    max-edge) args=("${inputs[@]}" --max-edge 20) ;;
    both) args=("${inputs[@]}" "${regions[@]}" --max-edge 20) ;;
  esac
  : >"$work/wall" && : >"$work/reg"
  for r in $(seq 0 "$runs"); do
    t0=$(date +%s%N)
    cdt triangulate "${args[@]}" -o "$work/$mode-$r.ply" --stats "$work/$mode.json" -q "$@"
    t1=$(date +%s%N)
    [ "$r" -eq 0 ] && continue  # warm-up
    echo $(( (t1 - t0) / 1000000 )) >>"$work/wall"
    stage "$work/$mode.json" regions >>"$work/reg"
    [ "$r" -gt 1 ] && rm -f "$work/$mode-$r.ply"
  done
  same=$(cmp -s "$work/$mode-0.ply" "$work/$mode-1.ply" && echo yes || echo no)
  tris=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['counts'].get('triangles', '?'))" "$work/$mode.json")
  printf '%-18s %10s %10s %12s %12s\n' "$mode" "$(median <"$work/wall")" "$(median <"$work/reg")" "$tris" "$same"
  cp "$work/$mode.json" "$out/regions-$size-$mode.json"
  [ "$mode" = plain ] || cdt triangulate "${args[@]}" -o "$work/$mode-v.ply" -v "$@" 2>&1 | grep -o "regions:.*" || true
done
