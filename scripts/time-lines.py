#!/usr/bin/env python3
# Runs a command N times and times its stderr lines as they arrive: spawn -> first line, last line -> exit
# (where a process's start and exit go), and the last run's lines with their times. With `-v`, cdtgpu logs each
# stage as it ends:
#   python3 scripts/time-lines.py 5 cdtgpu triangulate pts.xyz lines.wkt -o out.ply -v
import subprocess
import sys
import time

runs = int(sys.argv[1])
cmd = sys.argv[2:]
for r in range(runs):
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
    lines = [(time.monotonic() - t0, line.rstrip()) for line in p.stderr]
    p.wait()
    wall = time.monotonic() - t0
    first = lines[0][0] if lines else float("nan")
    last = lines[-1][0] if lines else float("nan")
    print(f"run {r}: wall {wall * 1e3:.1f} ms, first line {first * 1e3:.1f} ms, last line {last * 1e3:.1f} ms, "
          f"after last {(wall - last) * 1e3:.1f} ms")
    if r == runs - 1:
        for t, line in lines:
            print(f"  {t * 1e3:8.1f} {line[:150]}")
