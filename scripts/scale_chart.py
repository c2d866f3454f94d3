#!/usr/bin/env python3
"""Chart and exponents of the scale measurement (`scripts/scale`): time and peak memory of every stage against the
number of vertices, log-log, one line per stage and source, with the exponent of a least-squares fit of
log(y) = a + b·log(vertices) in the legend. Prints the table and the exponents as Markdown.

    .venv-notebooks/bin/python scripts/scale_chart.py docs/scale/scale.csv docs/scale.png
"""
import csv
import math
import sys
from pathlib import Path

from chart_cli import pyplot  # scripts/chart_cli.py, beside this script

plt = pyplot(__doc__, " [CSV] [PNG]", 2)

BUILD_STAGES = [
    ("load_s", "build: read + Delaunay"),
    ("horizon_s", "build: horizons"),
    ("regions_s", "build: regions"),
    ("grouping_s", "build: grouping"),
    ("build_s", "build: total (wall)"),
    ("build_user_s", "build: total (user CPU)"),
]
OTHER_STAGES = [
    ("tin_s", "tin (DEM → TIN)"),
    ("truth_s_per_viewpoint", "eval: ground truth / viewpoint"),
    ("cull_safe_ground_us", "cull safe, ground (µs → s)"),
    ("cull_thesis_ground_us", "cull thesis, ground (µs → s)"),
]
MEMORY_STAGES = [("tin_peak_mb", "tin"), ("build_peak_mb", "build"), ("eval_peak_mb", "eval")]
SOURCES = {"synth": ("synthetic", "-"), "cascades": ("N43W123", "--")}


def number(x):
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) and v > 0 else None


def fit(xs, ys):
    """Least-squares slope of log(y) against log(x), or None with fewer than two points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys)]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else None


def series(rows, key):
    pts = [(int(r["vertices"]), number(r.get(key))) for r in rows]
    pts = sorted((x, y) for x, y in pts if y is not None)
    return [p[0] for p in pts], [p[1] for p in pts]


def read_table(path):
    """The rows of a `scripts/scale` table, by source then vertices; exits naming the file and line at fault."""
    name = sys.argv[0]
    try:
        with path.open(newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
            columns = reader.fieldnames or []
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        sys.exit(f"{name}: cannot read {path}: {getattr(e, 'strerror', None) or e}")
    missing = [c for c in ("source", "vertices", "triangles", "threads") if c not in columns]
    if missing:
        sys.exit(f"{name}: {path} is not a scripts/scale table (no column {', '.join(missing)})")
    stages = [key for key, _ in BUILD_STAGES + OTHER_STAGES + MEMORY_STAGES]
    if not any(key in columns for key in stages):
        sys.exit(f"{name}: {path} has no measurement column (such as {', '.join(stages[:3])})")
    for line, r in enumerate(rows, start=2):
        for count in ("vertices", "triangles"):
            if not (r[count] or "").isdigit():
                sys.exit(f"{name}: {path}, line {line}: {count} {r[count]!r} is not a count")
    order = list(SOURCES)
    return sorted(rows, key=lambda r: (order.index(r["source"]) if r["source"] in order else len(order),
                                       int(r["vertices"])))


def main():
    path = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/scale/scale.csv")
    png = Path(sys.argv[2] if len(sys.argv) > 2 else "docs/scale.png")
    rows = read_table(path)
    fig, (ax_t, ax_o, ax_m) = plt.subplots(1, 3, figsize=(18, 8.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    exponents = []
    for src, (title, style) in SOURCES.items():
        mine = [r for r in rows if r["source"] == src]
        if not mine:
            continue
        for ax, stages in ((ax_t, BUILD_STAGES), (ax_o, OTHER_STAGES)):
            for i, (key, label) in enumerate(stages):
                xs, ys = series(mine, key)
                if key.endswith("_us"):
                    ys = [y / 1e6 for y in ys]
                b = fit(xs, ys)
                if not xs:
                    continue
                exponents.append((title, label, b))
                ax.plot(xs, ys, style, marker="o", color=colours[i % len(colours)],
                        label=f"{title}: {label}" + (f" (n^{b:.2f})" if b is not None else ""))
        for i, (key, label) in enumerate(MEMORY_STAGES):
            xs, ys = series(mine, key)
            b = fit(xs, ys)
            if not xs:
                continue
            exponents.append((title, f"peak memory: {label}", b))
            ax_m.plot(xs, ys, style, marker="o", color=colours[i % len(colours)],
                      label=f"{title}: {label}" + (f" (n^{b:.2f})" if b is not None else ""))
    threads = sorted({r["threads"] for r in rows if r.get("threads")})
    ax_t.set_title(f"build, per stage ({', '.join(threads) or '?'} threads; shared, loaded 2-core machine)",
                   fontsize=10)
    ax_t.set_ylabel("seconds")
    ax_o.set_title("tin, ground truth per viewpoint, cull per view", fontsize=10)
    ax_o.set_ylabel("seconds")
    ax_m.set_title("Peak resident memory per command", fontsize=10)
    ax_m.set_ylabel("MB")
    for ax in (ax_t, ax_o, ax_m):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("vertices")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=1)
    fig.suptitle("tincull at scale: solid = synthetic (synth --rng-seed 1), dashed = N43W123 (tin --vertices N); "
                 "16×4 sectors", fontsize=10)
    fig.tight_layout()
    try:
        png.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(png, dpi=110)
    except OSError as e:
        sys.exit(f"{sys.argv[0]}: cannot write {png}: {e.strerror or e}")
    print(f"wrote {png}")

    def cell(r, key, fmt):
        v = number(r.get(key))
        return fmt.format(v) if v is not None else "–"

    print()
    print("| source | vertices | triangles | tin s | read + Delaunay s | horizons s | regions s | grouping s "
          "| build s (wall) | build s (user) | build peak MB | cull µs safe ground / high | cull µs thesis ground / high "
          "| truth s / viewpoint |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print(f"| {SOURCES.get(r['source'], (r['source'],))[0]} | {int(r['vertices']):,} | {int(r['triangles']):,} "
              f"| {cell(r, 'tin_s', '{:.1f}')} | {cell(r, 'load_s', '{:.2f}')} | {cell(r, 'horizon_s', '{:.2f}')} "
              f"| {cell(r, 'regions_s', '{:.2f}')} | {cell(r, 'grouping_s', '{:.2f}')} | {cell(r, 'build_s', '{:.1f}')} "
              f"| {cell(r, 'build_user_s', '{:.1f}')} | {cell(r, 'build_peak_mb', '{:.0f}')} "
              f"| {cell(r, 'cull_safe_ground_us', '{:.0f}')} / {cell(r, 'cull_safe_high_us', '{:.0f}')} "
              f"| {cell(r, 'cull_thesis_ground_us', '{:.1f}')} / {cell(r, 'cull_thesis_high_us', '{:.1f}')} "
              f"| {cell(r, 'truth_s_per_viewpoint', '{:.2f}')} |")
    print()
    titles = [t for t, _ in SOURCES.values() if any(e[0] == t for e in exponents)]
    print("| stage | " + " | ".join(f"exponent, {t}" for t in titles) + " |")
    print("| --- |" + " ---: |" * len(titles))
    labels = list(dict.fromkeys(e[1] for e in exponents))
    found = {(t, label): b for t, label, b in exponents}
    for label in labels:
        cells = [found.get((t, label)) for t in titles]
        print(f"| {label} | " + " | ".join("–" if b is None else f"{b:.2f}" for b in cells) + " |")


if __name__ == "__main__":
    main()
