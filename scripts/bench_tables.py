#!/usr/bin/env python3
"""Markdown tables of docs/performance.md from `cdtgpu bench --json` files.

    scripts/bench_tables.py docs/bench/h100-{t1,t2,dt,long,terrain}.json docs/bench/h100-ablation.json

Prints, per file, the table rows (a table file) or the ablation table (an --ablation file), and for the 2M +
500K row of table 1 the GPU stages and host-clock stages ("where the time goes")."""
import json
import sys

HEADER = ("| points | vertices | constraints | CGAL ms | GPU ms | wall ms | speedup (wall) | speedup (GPU ms) "
          "| rounds | B/pt |\n|---|---|---|---|---|---|---|---|---|---|")


def ms(v):
    return f"{v:.1f}" if v < 100 else f"{v:.0f}"


def thousands(v):
    return f"{int(round(v)):,}".replace(",", " ")


def label(r):
    if r["workload"] == "grid":
        return r["sources"][0].replace("(", " ").rstrip(")")  # grid(2000x2000) -> grid 2000x2000
    m = r["points"] / 1e6
    return f"{m:g}M" if abs(m * 2 - round(m * 2)) < 1e-9 else f"{m:.2f}M"


def table(rows):
    print(HEADER)
    for r in rows:
        c, g, w = r["cgal"]["median_ms"], r["gpu"]["device_median_ms"], r["gpu"]["median_ms"]
        print(f"| {label(r)} | {r['vertices']} | {r['constraints']} | {thousands(c)} | {g:.1f} | {ms(w)} | "
              f"{c / w:.1f}x | {c / g:.0f}x | {r['gpu']['rounds']} | {r['gpu']['peak_device_bytes'] / r['vertices']:.0f} |")


def stages(r):
    gpu = {k: v for k, v in r["gpu"]["stage_median_ms"].items() if "(host)" not in k and k != "host overhead"}
    print("| GPU stage (device timestamps) | ms |\n|---|---|")
    for k, v in gpu.items():
        print(f"| {k} | {v:.2f} |")
    print(f"| **total** | **{sum(gpu.values()):.2f}** |\n")
    wall = r["gpu"].get("wall_stage_median_ms", {})
    if wall:
        print("| host clock, per pipeline stage | ms |\n|---|---|")
        for k, v in wall.items():
            print(f"| {k} | {v:.1f} |")
        print(f"| **wall total** | **{r['gpu']['median_ms']:.1f}** |")


def ablation(doc):
    print("| constraints | variant | GPU ms | vs full | wall ms | constraint insertion ms | rounds | B/pt | host fallback |")
    print("|---|---|---|---|---|---|---|---|---|")
    for w in doc["workloads"]:
        full = w["variants"][0]["device_median_ms"]
        for i, v in enumerate(w["variants"]):
            head = f"{w['constraints']} (CGAL {w['cgal']['median_ms']:.0f} ms)" if i == 0 else ""
            print(f"| {head} | {v['variant']} | {v['device_median_ms']:.2f} | {100 * (v['device_median_ms'] / full - 1):+.0f} % | "
                  f"{v['median_ms']:.0f} | {v['constraint_insertion_ms']:.2f} | {v['rounds']} | "
                  f"{v['peak_device_bytes'] / w['vertices']:.0f} | {v['host_fallback_constraints']} |")


for path in sys.argv[1:]:
    doc = json.load(open(path))
    print(f"\n{path}\n")
    if "workloads" in doc:
        ablation(doc)
        continue
    table(doc["rows"])
    for r in doc["rows"]:
        if r["table"] == "1" and r["points"] == 2000000:
            print()
            stages(r)
