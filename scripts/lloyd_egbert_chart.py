#!/usr/bin/env python3
"""Chart of issue 13: cull time against occlusion captured, Lloyd & Egbert's horizon culling against the other methods.

Reads the CSVs of `cargo run --release -p eval --example lloyd_egbert_compare` in docs/lloyd_egbert/ and writes
docs/lloyd_egbert.png. Needs matplotlib (`scripts/charts` installs it into .venv-notebooks):

    .venv-notebooks/bin/python scripts/lloyd_egbert_chart.py
"""
import csv
from pathlib import Path

from chart_cli import pyplot  # scripts/chart_cli.py, beside this script

plt = pyplot(__doc__)

root = Path(__file__).resolve().parent.parent / "docs"
meshes = [("jacksboro-10k", "jacksboro-10k.csv"), ("Cascades 100k", "cascades-100k.csv")]
fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
for ax, (title, name) in zip(axes, meshes):
    rows = [r for r in csv.DictReader(open(root / "lloyd_egbert" / name)) if r["class"] == "all"]
    us = lambda r: float(r["cull_ns"]) / 1000.0  # noqa: E731
    cap = lambda r: float(r["captured"])  # noqa: E731
    colours = {"4": "tab:blue", "5": "tab:orange", "6": "tab:green"}
    for depth, colour in colours.items():
        le = sorted((r for r in rows if r["method"] == "lloyd-egbert" and r["depth"] == depth),
                    key=lambda r: int(r["columns"]))
        if not le:
            continue
        ax.plot([us(r) for r in le], [cap(r) for r in le], "o-", color=colour,
                label=f"lloyd-egbert, quadtree depth {depth}")
        for r in le:
            ax.annotate(r["columns"], (us(r), cap(r)), textcoords="offset points", xytext=(4, -9), fontsize=7,
                        color=colour)
        for r in rows:
            if r["method"] == "stewart" and r["depth"] == depth:
                ax.plot(us(r), cap(r), "x", color=colour, markersize=8,
                        label=f"stewart, depth {depth} (fc {r['viewpoints_with_false_culls']} views)")
    for method, marker, colour in [("safe", "s", "black"), ("thesis", "D", "tab:red")]:
        for r in rows:
            if r["method"] == method and r["grouping"] == "crystal":
                extra = "" if method == "safe" else f" (fc {r['viewpoints_with_false_culls']} views)"
                ax.plot(us(r), cap(r), marker, color=colour, markersize=8, markerfacecolor="none",
                        label=f"{method}, crystal{extra}")
    ax.set_xscale("log")
    ax.set_xlabel("median cull time per view (µs, log)")
    ax.set_ylabel("occlusion captured (all classes)")
    ax.set_ylim(0, 1)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6.5, loc="upper left")
fig.suptitle("Cull time against occlusion captured, 120 viewpoints, 360° (labels: horizon columns per face; "
             "fc = viewpoints with false culls)", fontsize=9)
fig.tight_layout()
fig.savefig(root / "lloyd_egbert.png", dpi=110)
print(root / "lloyd_egbert.png")
