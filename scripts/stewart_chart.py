#!/usr/bin/env python3
"""Chart of issue 14: occlusion captured against visibility bytes, Stewart's quadtree against the crystal hierarchy.

Reads the CSVs of `cargo run --release -p eval --example stewart_compare` in docs/stewart/ and writes
docs/stewart/bytes_vs_captured.png. Needs matplotlib (`scripts/charts` installs it into .venv-notebooks):

    .venv-notebooks/bin/python scripts/stewart_chart.py
"""
import csv
from pathlib import Path

from chart_cli import pyplot  # scripts/chart_cli.py, beside this script

plt = pyplot(__doc__)

root = Path(__file__).resolve().parent.parent / "docs" / "stewart"
meshes = [("jacksboro-10k", "jacksboro-10k.csv"), ("Cascades 100k", "cascades-100k.csv")]
fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
for ax, (title, name) in zip(axes, meshes):
    rows = [r for r in csv.DictReader(l for l in open(root / name) if not l.startswith("#")) if r["class"] == "all"]
    for sk, colour in [("16x4", "tab:blue"), ("64x4", "tab:orange")]:
        s, k = sk.split("x")
        mine = [r for r in rows if r["sectors"] == s and r["subsectors"] == k and r["method"] in ("thesis", "stewart")]
        quad = sorted((r for r in mine if r["grouping"] == "quadtree"), key=lambda r: int(r["bytes"]))
        crys = [r for r in mine if r["grouping"] == "crystal"]
        ax.plot([int(r["bytes"]) for r in quad], [float(r["captured"]) for r in quad], "o-", color=colour,
                label=f"quadtree (stewart) {sk}")
        for r in quad:
            ax.annotate(f"d{r['depth']}, fc {float(r['false_culls_mean']):.1f}", (int(r["bytes"]), float(r["captured"])),
                        textcoords="offset points", xytext=(4, -10), fontsize=7, color=colour)
        for r in crys:
            ax.plot(int(r["bytes"]), float(r["captured"]), "s", color=colour, markersize=9, markerfacecolor="none",
                    label=f"crystal (thesis) {sk}")
            ax.annotate(f"fc {float(r['false_culls_mean']):.1f}", (int(r["bytes"]), float(r["captured"])),
                        textcoords="offset points", xytext=(4, 4), fontsize=7, color=colour)
    ax.set_xscale("log")
    ax.set_xlabel("visibility bytes")
    ax.set_ylabel("occlusion captured (all classes)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
fig.suptitle("Region test per node: Stewart's quadtree vs crystals, same horizons (fc = false culls per viewpoint)",
             fontsize=9)
fig.tight_layout()
fig.savefig(root / "bytes_vs_captured.png", dpi=110)
print(root / "bytes_vs_captured.png")
