#!/usr/bin/python3
"""Plots one or more `cdtgpu bench --json` files (the paper's Fig. 8/9/10). Rows of all files are merged and
grouped by their "table" ("1", "2", "long", "terrain", "dt", ...).

  time.png             per table: CGAL median, GPU backend wall median, GPU device time (sum of GPU timestamps)
  speedup.png          per table: speedup over CGAL by wall time and by device time
  stages_gpu.png       stacked bars per row of the GPU device stages (host stages left out)   (Fig. 10)
  stages_gpu_wall.png  stacked bars per row of the GPU wall time: resolve, upload, device total, download,
                       host overhead
  stages_cgal.png      stacked bars per row of the CGAL stages
  ablation.png         only if a `cdtgpu bench --ablation` JSON is given: GPU device ms of each variant against
                       the constraint count (the shape of the paper's Table 3)
  ablation_<m>.png     per ablation workload (m constraints): device, wall and constraint-insertion ms per variant

Where a table mixes workloads (the dt table: uniform rows plus one grid row), the lines follow the most common
workload and the other rows are drawn as separate markers.

Usage: scripts/plot_bench.py bench.json [more.json ...] [-o OUTDIR]   (OUTDIR defaults to the first JSON's folder)
Needs python3-matplotlib (Debian)."""
import argparse
import json
import os
import sys
import textwrap
from collections import Counter

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

TABLE_TITLES = {
    "1": "Table 1: points vary, constraints fixed",
    "2": "Table 2: constraints vary, points fixed",
    "long": "Long constraints: points vary",
    "terrain": "Terrain (DEM + contours): points vary",
    "dt": "Delaunay only: points vary",
}
TABLE_ORDER = ["1", "2", "long", "terrain", "dt"]

# Fixed colours: dt stages blue, cdt insertion orange/brown, cdt legalisation green, canonical order purple.
GPU_STAGE_COLOURS = {
    "dt start": "#c6dbef",
    "dt relocate": "#6baed6",
    "dt insert": "#2171b5",
    "dt flip": "#08306b",
    "cdt vertex map": "#fdd0a2",
    "cdt crossing detection": "#fd8d3c",
    "cdt prefix-sum layout": "#d94801",
    "cdt flipping": "#7f2704",
    "cdt mark constrained": "#c7e9c0",
    "cdt legalise seed": "#74c476",
    "cdt legalise": "#00441b",
    "canonical order": "#807dba",
}
DEVICE_TOTAL = "GPU stages (device total)"
WALL_PARTS = ["resolve (host)", "upload (host)", DEVICE_TOTAL, "download (host)", "host overhead"]
WALL_COLOURS = {
    "resolve (host)": "#969696",
    "upload (host)": "#9ecae1",
    DEVICE_TOTAL: "#2171b5",
    "download (host)": "#fc9272",
    "host overhead": "#d9d9d9",
}
CGAL_STAGE_COLOURS = {"points": "#2ca02c", "constraints": "#ff7f0e", "extract": "#9467bd"}
FALLBACK = plt.get_cmap("tab20").colors

L_CGAL = "CGAL (fast config)"
L_WALL = "GPU backend, wall"
L_DEV = "GPU stages, device timestamps"


def is_host_stage(name):
    return name.endswith("(host)") or name == "host overhead"


def x_of(table, row):
    """Table 2 varies the constraint count, the others the point count."""
    return row["constraints"] if table == "2" else row["vertices"]


def count_fmt(x, _pos=None):
    """1500000 -> 1.5M, 25426 -> 25.4K (axis ticks and bar labels)."""
    return "0" if x == 0 else "%.3gM" % (x / 1e6) if abs(x) >= 1e6 else "%.3gK" % (x / 1e3)


def x_label(table):
    return "constraints" if table == "2" else "vertices"


def by_table(rows):
    tables = {}
    for r in rows:
        tables.setdefault(str(r["table"]), []).append(r)
    for t in tables.values():
        t.sort(key=lambda r: (r["vertices"], r["constraints"]))
    known = [t for t in TABLE_ORDER if t in tables]
    return {t: tables[t] for t in known + sorted(set(tables) - set(known))}


def split_workloads(rows):
    """(rows of the table's most common workload, the other rows)."""
    main = Counter(r.get("workload") for r in rows).most_common(1)[0][0]
    return [r for r in rows if r.get("workload") == main], [r for r in rows if r.get("workload") != main]


def extra_name(r):
    return "%s %dx%d" % (r["workload"], r["grid"], r["grid"]) if r.get("workload") == "grid" and r.get("grid") \
        else str(r.get("workload"))


def table_title(t, rows):
    title = TABLE_TITLES.get(t, "Table %s" % t)
    main, extra = split_workloads(rows)
    if extra:
        title += "\n(lines: %s rows; %s marked separately)" % (
            main[0].get("workload"), ", ".join(sorted({extra_name(r) for r in extra})))
    return title


def row_label(r):
    lab = "%s\n%s/%s" % (r["table"], count_fmt(r["vertices"]), count_fmt(r["constraints"]))
    return lab + "\n" + r["workload"] if r.get("workload") == "grid" else lab


def header(meta):
    """Device, CPU and date(s) of the merged files."""
    m = meta["machine"]
    gpus = sorted({x.get("gpu") for x in meta["machines"] if x.get("gpu")})
    dates = sorted(meta["dates"])
    date = dates[0] if len(dates) == 1 else ", ".join(sorted({d[:10] for d in dates}))
    return "%s; %s, %s thread(s); %s" % (" / ".join(gpus) or "no GPU named", m.get("cpu", "?"),
                                         m.get("hardware_threads", "?"), date or "?")


def grid_axes(n, w=4.6, h=3.6, ncols=3):
    ncols = min(n, ncols)
    nrows = (n + ncols - 1) // ncols
    w = max(w, 8.0 / ncols)  # room for the title and legend when there are few tables
    fig, axes = plt.subplots(nrows, ncols, figsize=(w * ncols, h * nrows + 0.9), squeeze=False)
    flat = list(axes.flat)
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def save(fig, out):
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)
    return out


def series(ax, t, rows, key, style, label, colour):
    """One line over the main workload rows, plus unconnected markers for the other rows."""
    main, extra = split_workloads(rows)
    pts = [(x_of(t, r), key(r)) for r in main if key(r) is not None]
    if pts:
        ax.plot([a for a, _ in pts], [b for _, b in pts], style, label=label, color=colour, ms=4)
    for r in extra:  # open markers; style_axis adds one legend entry for them
        y = key(r)
        if y is not None:
            ax.plot([x_of(t, r)], [y], style[0], color=colour, ms=9, mfc="none", mew=1.5)


def gpu_get(field):
    return lambda r: r["gpu"].get(field) if r.get("gpu") else None


def style_axis(ax, t, rows, ylabel):
    extra = split_workloads(rows)[1]
    if extra:
        ax.plot([], [], "o", color="grey", ms=9, mfc="none", mew=1.5,
                label="open: " + ", ".join(sorted({extra_name(r) for r in extra})))
    ax.xaxis.set_major_formatter(FuncFormatter(count_fmt))
    ax.set_title(table_title(t, rows), fontsize=8)
    ax.set_xlabel(x_label(t), fontsize=8)
    ax.set_ylabel(ylabel, fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)


def shared_legend_save(fig, axes, title, out):
    """One legend for all subplots (same lines everywhere), under the title."""
    seen = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    w, h = fig.get_size_inches()
    fig.suptitle(title, fontsize=9, y=1 - 0.05 / h, va="top")
    ncol = len(seen) if w > 10 else 2
    fig.legend(list(seen.values()), list(seen), loc="upper center", ncol=ncol, fontsize=8,
               bbox_to_anchor=(0.5, 1 - 0.42 / h), frameon=False)
    top = 0.3 + 0.2 * ((len(seen) + ncol - 1) // ncol)  # inches for title and legend (tight_layout adds a pad)
    fig.tight_layout(rect=(0, 0, 1, 1 - top / h))
    fig.savefig(out, dpi=130)
    plt.close(fig)
    return out


def plot_times(meta, tables, out):
    fig, axes = grid_axes(len(tables))
    for ax, (t, rows) in zip(axes, tables.items()):
        series(ax, t, rows, lambda r: r["cgal"]["median_ms"], "o-", L_CGAL, "C0")
        if any(r.get("gpu") for r in rows):
            series(ax, t, rows, gpu_get("median_ms"), "s-", L_WALL, "C1")
            series(ax, t, rows, gpu_get("device_median_ms"), "^-", L_DEV, "C2")
        style_axis(ax, t, rows, "median ms")
    return shared_legend_save(fig, axes, "cdtgpu bench: time per triangulation\n%s" % header(meta), out)


def plot_speedup(meta, tables, out):
    with_gpu = {t: [r for r in rows if r.get("speedup")] for t, rows in tables.items()}
    with_gpu = {t: rows for t, rows in with_gpu.items() if rows}
    if not with_gpu:
        print("no GPU figures in the JSON: speedup plot skipped")
        return None
    fig, axes = grid_axes(len(with_gpu))
    for ax, (t, rows) in zip(axes, with_gpu.items()):
        series(ax, t, rows, lambda r: r.get("speedup"), "s-", "by wall time (CGAL / GPU wall)", "C1")
        series(ax, t, rows, lambda r: r.get("speedup_device"), "^-", "by device time (CGAL / GPU device)", "C2")
        style_axis(ax, t, rows, "speedup over CGAL (x)")
    return shared_legend_save(fig, axes, "GPU backend speedup over CGAL\n%s" % header(meta), out)


def stacked(meta, rows, parts, colours, title, ylabel, out, wall_tick=None):
    """Stacked bars per row, tables separated by a gap. parts(r) -> {stage: ms}."""
    stages = []
    for r in rows:
        stages += [s for s in parts(r) if s not in stages]
    order = [s for s in colours if s in stages] + [s for s in stages if s not in colours]
    xs, prev = [], None
    for r in rows:  # gap of one bar between tables
        xs.append((xs[-1] + (1.8 if r["table"] != prev else 1.0)) if xs else 0.0)
        prev = r["table"]
    fig, ax = plt.subplots(figsize=(max(6.5, 0.5 * xs[-1] + 4.5), 4.6))
    bottom = [0.0] * len(rows)
    for i, s in enumerate(order):
        v = [parts(r).get(s, 0.0) for r in rows]
        ax.bar(xs, v, bottom=bottom, width=0.8, label=s, color=colours.get(s, FALLBACK[i % len(FALLBACK)]),
               edgecolor="white", linewidth=0.3)
        bottom = [a + b for a, b in zip(bottom, v)]
    if wall_tick:
        w = [wall_tick(r) for r in rows]
        ax.plot(xs, w, "_", color="black", ms=12, mew=1.5, label="GPU backend, wall median")
    ax.set_xticks(xs)
    ax.set_xticklabels([row_label(r) for r in rows], fontsize=6)
    ax.set_xlim(-0.8, xs[-1] + 0.8)
    ax.tick_params(axis="y", labelsize=7)
    ax.set_xlabel("table, vertices / constraints", fontsize=8)
    ax.set_ylabel(ylabel, fontsize=8)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), borderaxespad=0)
    ax.set_title("%s (%s)" % (title, header(meta)), fontsize=9)
    return save(fig, out)


def plot_stages_cgal(meta, rows, out):
    rows = [r for r in rows if r.get("cgal") and r["cgal"].get("stage_median_ms")]
    if not rows:
        print("no per-stage CGAL times in the JSON: stage plot skipped")
        return None
    return stacked(meta, rows, lambda r: r["cgal"]["stage_median_ms"], CGAL_STAGE_COLOURS, "CGAL stages",
                   "median ms per stage", out)


def plot_stages_gpu(meta, rows, out):
    rows = [r for r in rows if r.get("gpu") and r["gpu"].get("stage_median_ms")]
    if not rows:
        print("no per-stage GPU times in the JSON: stage plot skipped")
        return None
    return stacked(meta, rows,
                   lambda r: {s: v for s, v in r["gpu"]["stage_median_ms"].items() if not is_host_stage(s)},
                   GPU_STAGE_COLOURS, "GPU device stages (GPU timestamps, host stages left out)",
                   "median ms per stage (device)", out)


def wall_parts(r):
    s = r["gpu"]["stage_median_ms"]
    d = {k: s[k] for k in WALL_PARTS if k in s}
    d[DEVICE_TOTAL] = r["gpu"].get("device_median_ms") or sum(v for k, v in s.items() if not is_host_stage(k))
    return d


def plot_stages_gpu_wall(meta, rows, out):
    rows = [r for r in rows if r.get("gpu") and r["gpu"].get("stage_median_ms")]
    if not rows:
        return None
    return stacked(meta, rows, wall_parts, WALL_COLOURS, "GPU backend wall time split",
                   "median ms (host wall clock)", out, wall_tick=lambda r: r["gpu"]["median_ms"])


def plot_ablation(ab, out):
    vs = ab["variants"]
    bars = [("GPU device ms", "device_median_ms", "C2"), ("GPU wall ms", "median_ms", "C1"),
            ("constraint insertion ms (device)", "constraint_insertion_ms", "C3")]
    bars = [b for b in bars if any(v.get(b[1]) is not None for v in vs)]
    w = 0.8 / len(bars)
    fig, ax = plt.subplots(figsize=(max(6.5, 1.9 * len(vs) + 2), 4.4))
    for i, (lab, key, col) in enumerate(bars):
        xs = [j + (i - (len(bars) - 1) / 2) * w for j in range(len(vs))]
        ys = [v.get(key) or 0.0 for v in vs]
        ax.bar(xs, ys, width=w, label=lab, color=col)
        for x, y in zip(xs, ys):
            ax.annotate("%.1f" % y, (x, y), textcoords="offset points", xytext=(0, 2), ha="center", fontsize=6)
    ax.set_xticks(range(len(vs)))
    ax.set_xticklabels([textwrap.fill(v.get("variant", "?"), 24) + ("\n%d rounds" % v["rounds"] if "rounds" in v else "")
                        for v in vs], fontsize=7)
    ax.tick_params(axis="y", labelsize=7)
    ax.set_ylabel("median ms", fontsize=8)
    ax.set_ylim(0, 1.2 * max(v.get(k) or 0.0 for _, k, _ in bars for v in vs))  # room for the legend
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", ncol=len(bars))
    cg = ab.get("cgal", {}).get("median_ms")
    ax.set_title("Ablation, %s vertices / %s constraints%s\n(%s; %s)" % (
        count_fmt(ab.get("vertices", 0)), count_fmt(ab.get("constraints", 0)),
        ", CGAL %.0f ms" % cg if cg else "", ab.get("device", "?"), ab.get("date", "?")), fontsize=9)
    return save(fig, out)


def plot_ablation_sweep(ab, out):
    """GPU device ms of every variant against the constraint count: the shape of the paper's Table 3."""
    ws = ab["workloads"]
    names = [v["variant"] for v in ws[0]["variants"]]
    fig, ax = plt.subplots(figsize=(7.5, 4.4))
    for i, name in enumerate(names):
        xs = [w["constraints"] for w in ws]
        ys = [w["variants"][i].get("device_median_ms") or 0.0 for w in ws]
        ax.plot(xs, ys, "o-", label=name, color="C%d" % i)
    ax.xaxis.set_major_formatter(FuncFormatter(count_fmt))
    ax.set_xlabel("constraints", fontsize=8)
    ax.set_ylabel("GPU ms (device timestamps, median)", fontsize=8)
    ax.set_ylim(bottom=0)
    ax.tick_params(labelsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("Ablation, %s points\n(%s; %s)" % (count_fmt(ab.get("points", 0)), ab.get("device", "?"),
                                                  ab.get("date", "?")), fontsize=9)
    return save(fig, out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json", nargs="+", help="files written by cdtgpu bench --json (or bench --ablation)")
    ap.add_argument("-o", "--outdir", help="folder for the PNG files (default: the first JSON's folder)")
    args = ap.parse_args()
    rows, ablations = [], []
    meta = {"machine": {}, "machines": [], "dates": set()}
    for path in args.json:
        with open(path) as f:
            data = json.load(f)
        if "workloads" in data or "variants" in data:
            ablations.append(data)
            continue
        if not data.get("rows"):
            sys.exit("%s: no rows" % path)
        rows += data["rows"]
        meta["machine"] = meta["machine"] or data.get("machine", {})
        meta["machines"].append(data.get("machine", {}))
        meta["dates"].add(data.get("date", "?"))
    outdir = args.outdir or os.path.dirname(os.path.abspath(args.json[0]))
    os.makedirs(outdir, exist_ok=True)
    written = []
    if rows:
        tables = by_table(rows)
        ordered = [r for t in tables.values() for r in t]
        written += [
            plot_times(meta, tables, os.path.join(outdir, "time.png")),
            plot_speedup(meta, tables, os.path.join(outdir, "speedup.png")),
            plot_stages_cgal(meta, ordered, os.path.join(outdir, "stages_cgal.png")),
            plot_stages_gpu(meta, ordered, os.path.join(outdir, "stages_gpu.png")),
            plot_stages_gpu_wall(meta, ordered, os.path.join(outdir, "stages_gpu_wall.png")),
        ]
    for i, ab in enumerate(ablations):
        suffix = "" if i == 0 else "_%d" % (i + 1)
        if "workloads" not in ab:  # an older file: one workload
            written.append(plot_ablation(ab, os.path.join(outdir, "ablation%s.png" % suffix)))
            continue
        written.append(plot_ablation_sweep(ab, os.path.join(outdir, "ablation%s.png" % suffix)))
        for w in ab["workloads"]:
            one = dict(w, device=ab.get("device"), date=ab.get("date"))
            written.append(plot_ablation(one, os.path.join(outdir, "ablation%s_%d.png" % (suffix, w["constraints"]))))
    for w in written:
        if w:
            print("wrote", w)


if __name__ == "__main__":
    main()
