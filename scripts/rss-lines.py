#!/usr/bin/env python3
# Runs a command once, samples its resident memory every 5 ms and prints each stderr line with the time it
# arrived and the most memory held since the line before (with cdtgpu -v: the memory of each stage):
#   python3 scripts/rss-lines.py cdtgpu triangulate pts.xyz lines.wkt -o out.ply --max-tile-points 16000000 -v
import subprocess
import sys
import threading
import time

cmd = sys.argv[1:]
t0 = time.monotonic()
p = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True)
samples = []


def sample():
    while p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/status") as f:
                for line in f:
                    if line.startswith("VmRSS"):
                        samples.append((time.monotonic() - t0, int(line.split()[1]) / 1e6))
        except OSError:
            pass
        time.sleep(0.005)


thread = threading.Thread(target=sample)
thread.start()
# Each line printed as it arrives (a run cut short keeps what it said), with the most memory since the line before.
i = 0
for line in p.stderr:
    t = time.monotonic() - t0
    peak = 0.0
    while i < len(samples) and samples[i][0] <= t:
        peak = max(peak, samples[i][1])
        i += 1
    print(f"{t * 1e3:8.0f} ms  max {peak:6.2f} GB  {line.rstrip()[:400]}", flush=True)
p.wait()
thread.join()
print("peak resident", max((s[1] for s in samples), default=0), "GB")
