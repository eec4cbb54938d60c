#!/usr/bin/python3
"""Plots a `cdtgpu bench --json` file: time vs size per table (CGAL and GPU where present), speedup, and
per-stage stacked bars for every backend that reports stages (CGAL always, GPU once it exists).

Usage: scripts/plot_bench.py bench.json [-o OUTDIR]   (writes time.png, speedup.png, stages_<backend>.png)
Needs python3-matplotlib (Debian)."""
import argparse
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402

TABLE_TITLES = {
    "1": "Table 1: points vary, constraints fixed",
    "2": "Table 2: constraints vary, points fixed",
    "long": "Long constraints: points vary",
    "terrain": "Terrain (DEM + contours): points vary",
}


def x_of(table, row):
    """Table 2 varies the constraint count, the others the point count."""
    return row["constraints"] if table == "2" else row["vertices"]


def x_label(table):
    return "constraints" if table == "2" else "vertices"


def by_table(rows):
    tables = {}
    for r in rows:
        tables.setdefault(r["table"], []).append(r)
    for t in tables.values():
        t.sort(key=lambda r: (r["vertices"], r["constraints"]))
    return tables


def subplots(n):
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 3.8), squeeze=False)
    return fig, axes[0]


def header(data):
    m = data.get("machine", {})
    return "%s, %s thread(s), %s" % (m.get("cpu", "?"), m.get("hardware_threads", "?"), data.get("date", "?"))


def plot_times(data, tables, gpu_name, out):
    fig, axes = subplots(len(tables))
    for ax, (t, rows) in zip(axes, tables.items()):
        xs = [x_of(t, r) for r in rows]
        ax.plot(xs, [r["cgal"]["median_ms"] for r in rows], "o-", label="CGAL (fast config)")
        if any(r.get("gpu") for r in rows):
            g = [(x_of(t, r), r["gpu"]["median_ms"]) for r in rows if r.get("gpu")]
            ax.plot([a for a, _ in g], [b for _, b in g], "s-", label=gpu_name)
        ax.set_title(TABLE_TITLES.get(t, t), fontsize=9)
        ax.set_xlabel(x_label(t))
        ax.set_ylabel("median ms")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("cdtgpu bench: CDT time (%s)" % header(data), fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def plot_speedup(data, tables, gpu_name, out):
    with_gpu = {t: [r for r in rows if r.get("speedup")] for t, rows in tables.items()}
    with_gpu = {t: rows for t, rows in with_gpu.items() if rows}
    if not with_gpu:
        print("no GPU figures in the JSON: speedup plot skipped")
        return None
    fig, axes = subplots(len(with_gpu))
    for ax, (t, rows) in zip(axes, with_gpu.items()):
        ax.plot([x_of(t, r) for r in rows], [r["speedup"] for r in rows], "o-")
        ax.set_title(TABLE_TITLES.get(t, t), fontsize=9)
        ax.set_xlabel(x_label(t))
        ax.set_ylabel("speedup over CGAL (x)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    fig.suptitle("%s speedup over CGAL (%s)" % (gpu_name, header(data)), fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def plot_stages(data, rows, backend, title, out):
    rows = [r for r in rows if r.get(backend) and r[backend].get("stage_median_ms")]
    if not rows:
        print("no per-stage %s times in the JSON: stage plot skipped" % backend)
        return None
    stages = []
    for r in rows:
        for s in r[backend]["stage_median_ms"]:
            if s not in stages:
                stages.append(s)
    labels = ["%s\n%dK/%dK" % (r["table"], r["vertices"] // 1000, r["constraints"] // 1000) for r in rows]
    fig, ax = plt.subplots(figsize=(max(6, 0.55 * len(rows) + 2), 4.2))
    bottom = [0.0] * len(rows)
    for s in stages:
        v = [r[backend]["stage_median_ms"].get(s, 0.0) for r in rows]
        ax.bar(range(len(rows)), v, bottom=bottom, label=s)
        bottom = [a + b for a, b in zip(bottom, v)]
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels(labels, fontsize=7)
    ax.set_xlabel("table, vertices / constraints")
    ax.set_ylabel("median ms per stage")
    ax.legend(fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    ax.set_title("%s stages (%s)" % (title, header(data)), fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json", help="file written by cdtgpu bench --json")
    ap.add_argument("-o", "--outdir", help="folder for the PNG files (default: the JSON's folder)")
    args = ap.parse_args()
    with open(args.json) as f:
        data = json.load(f)
    rows = data.get("rows", [])
    if not rows:
        sys.exit("%s: no rows" % args.json)
    outdir = args.outdir or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(outdir, exist_ok=True)
    gpu_name = data.get("gpu_backend") or "GPU"
    tables = by_table(rows)
    written = [
        plot_times(data, tables, gpu_name, os.path.join(outdir, "time.png")),
        plot_speedup(data, tables, gpu_name, os.path.join(outdir, "speedup.png")),
        plot_stages(data, rows, "cgal", "CGAL", os.path.join(outdir, "stages_cgal.png")),
        plot_stages(data, rows, "gpu", gpu_name, os.path.join(outdir, "stages_gpu.png")),
    ]
    for w in written:
        if w:
            print("wrote", w)


if __name__ == "__main__":
    main()
