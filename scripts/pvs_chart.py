#!/usr/bin/env python3
"""Chart of from-region visibility (`tincull pvs --check`): mean PVS size over the mean union of the sampled visible
sets (log scale), and seconds per cell, against the ray-space resolution, per cell size and height band.

Reads the JSON reports in docs/pvs/ (one `tincull pvs FILE.tch --check N --cell-size S --above-ground H0,H1
--resolution 16,64,256 --view-seed 1 --json` per file, named MESH_SIZE_H0,H1.json) and writes docs/pvs.png. Needs
matplotlib (`scripts/charts` installs it into .venv-notebooks):

    .venv-notebooks/bin/python scripts/pvs_chart.py
"""
import json
from pathlib import Path

from chart_cli import pyplot  # scripts/chart_cli.py, beside this script

plt = pyplot(__doc__)

root = Path(__file__).resolve().parent.parent / "docs"
meshes = [("jacksboro-10k", "jacksboro-10k"), ("cascades-100k", "Cascades 100k")]
present = [(m, t) for m, t in meshes if list((root / "pvs").glob(f"{m}_*.json"))]
fig, axes = plt.subplots(len(present), 2, figsize=(11, 4.2 * len(present)), squeeze=False)
colours = {"50": "tab:blue", "100": "tab:orange", "300": "tab:green"}
for row, (mesh, title) in zip(axes, present):
    for path in sorted((root / "pvs").glob(f"{mesh}_*.json")):
        d = json.loads(path.read_text())
        size = f"{d['cell_size']:g}"
        band = d["height"]["above_ground"]
        style = "-" if band[1] <= 2 else "--"
        label = f"{size} m, {band[0]:g}–{band[1]:g} m ({d['cells']} cells)"
        kol = [r for r in d["rows"] if r["method"] == "koltun"]
        reg = [r for r in d["rows"] if r["method"] == "regions"]
        res = [r["resolution"] for r in kol]
        visible = d["mean_union_visible"]
        row[0].plot(res, [r["mean_pvs_triangles"] / visible for r in kol], style, marker="o", color=colours.get(size),
                    label=label)
        if reg:
            row[0].plot([res[0], res[-1]], [reg[0]["mean_pvs_triangles"] / visible] * 2, style,
                        color=colours.get(size), alpha=0.35, linewidth=3)
        row[1].plot(res, [r["mean_seconds_per_cell"] for r in kol], style, marker="o", color=colours.get(size),
                    label=label)
        for r in kol + reg:
            if r["misses"]:
                row[0].annotate(f"{r['misses']} misses", (r["resolution"] or res[0],
                                r["mean_pvs_triangles"] / visible), color="red")
    row[0].set_yscale("log")
    for ax in row:
        ax.set_xscale("log", base=2)
        ax.set_xlabel("ray-space resolution R (R × R)")
        ax.grid(alpha=0.3)
    row[0].set_ylabel("mean PVS / mean union of sampled visible sets")
    row[0].set_title(f"{title}: PVS size (Koltun; thick pale line: regions test)")
    row[1].set_ylabel("seconds per cell (Koltun)")
    row[1].set_title(f"{title}: time per cell")
    row[0].legend(fontsize=7)
fig.tight_layout()
fig.savefig(root / "pvs.png", dpi=110)
print(f"wrote {root / 'pvs.png'}")
