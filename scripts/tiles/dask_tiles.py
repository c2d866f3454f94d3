#!/usr/bin/env python3
"""Runs a tincull tiled build on a Dask distributed cluster.

One task per tile (`tincull tiles build PLAN --tile I`), then one merge task (`tincull tiles merge PLAN -o OUT`).
Each task runs the tincull CLI in a subprocess, so a worker needs the `tincull` binary and the plan's files (the
DEM and the plan's folder) at the same paths: a shared file system, as on any cluster. A failed tile is retried
(`--retries`); a tile's output is written atomically, so a retry or a lost worker never leaves half a file.

    scripts/tiles/dask_tiles.py plan.json -o terrain.tch --workers 4          # a local cluster of 4 processes
    scripts/tiles/dask_tiles.py plan.json -o terrain.tch --scheduler tcp://head:8786   # an existing cluster

Why Dask: its distributed scheduler is pure Python (a small, quick install from PyPI), starts a local cluster in
a second for tests, and reaches batch systems through dask-jobqueue (Slurm, PBS, SGE) without changing this
script; the jobs are coarse subprocesses, so nothing of Ray's shared-memory object store would be used.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
import uuid


def run_cli(args):
    """Runs the tincull CLI; returns its JSON report or raises with its error message."""
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed with status {done.returncode}: {done.stderr.strip()}")
    return json.loads(done.stdout)


def build_tile(tincull, plan, index, threads):
    """One tile job."""
    args = [tincull, "tiles", "build", plan, "--tile", str(index), "--json", "--quiet"]
    if threads:
        args += ["--jobs", str(threads)]
    return run_cli(args)


def merge(tincull, plan, out, _tiles):
    """The merge job; `_tiles` (the tile jobs' results) makes Dask run it after every tile."""
    return run_cli([tincull, "tiles", "merge", plan, "-o", out, "--json", "--quiet"])


def find_tincull(given):
    if given:
        # A bare name (`--tincull tincull`) is looked up on PATH, as a shell would.
        if os.sep not in given:
            return shutil.which(given) or os.path.abspath(given)
        return os.path.abspath(given)
    here = os.path.dirname(os.path.abspath(__file__))
    target = os.environ.get("CARGO_TARGET_DIR") or os.path.join(here, "..", "..", "target")
    built = os.path.join(target, "release", "tincull")
    if os.path.exists(built):
        return os.path.abspath(built)
    on_path = shutil.which("tincull")
    if on_path:
        return on_path
    sys.exit("error: no tincull binary: build it (cargo build --release) or pass --tincull PATH")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("plan", help="the plan from `tincull tiles plan`")
    p.add_argument("-o", "--out", required=True, help="the merged hierarchy (.tch)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler; without it a local cluster starts")
    p.add_argument("--workers", type=int, default=2, help="worker processes of the local cluster [2]")
    p.add_argument(
        "--threads",
        type=int,
        default=0,
        help="threads of each tile job [0: on a local cluster the cores shared among its workers, on a scheduler's "
        "workers every core of the machine a job runs on]",
    )
    p.add_argument("--retries", type=int, default=2, help="retries of a failed tile job [2]")
    p.add_argument("--tincull", help="the tincull binary [$CARGO_TARGET_DIR or target/, release/tincull there, else on PATH]")
    args = p.parse_args()
    if args.scheduler is None and args.workers < 1:
        p.error(f"--workers must be at least 1 (a local cluster of {args.workers} workers would never run a tile)")
    if args.retries < 0:
        p.error(f"--retries must be 0 or more, got {args.retries}")
    if args.threads < 0:
        p.error(f"--threads must be 0 (the default share of cores) or more, got {args.threads}")

    tincull = find_tincull(args.tincull)
    if not (os.path.isfile(tincull) and os.access(tincull, os.X_OK)):
        sys.exit(f"error: {tincull}: not an executable tincull binary (--tincull)")
    plan = os.path.abspath(args.plan)
    out = os.path.abspath(args.out)
    try:
        with open(plan) as f:
            listed = json.load(f)["tiles"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"error: {args.plan}: not a readable tincull plan: {e}")
    if not isinstance(listed, list):
        sys.exit(f"error: {args.plan}: not a tincull plan (its `tiles` is no list; `tiles plan -o` writes the plan)")
    tiles = len(listed)
    # What the merge would refuse after every tile was built: refused first.
    if os.path.isdir(out):
        sys.exit(f"error: {args.out}: is a directory (-o names the merged .tch file)")
    if not os.path.isdir(os.path.dirname(out)):
        sys.exit(f"error: {args.out}: its folder does not exist")

    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError as e:
        here = os.path.dirname(os.path.abspath(__file__))
        sys.exit(
            f"error: Dask is not installed for {sys.executable} ({e}): install it with "
            f"`{sys.executable} -m pip install -r {os.path.join(here, 'requirements.txt')}`, or run "
            "scripts/tiles-dask, which makes .venv-tiles with it"
        )

    start = time.time()
    cluster = None
    threads = args.threads
    if threads == 0 and not args.scheduler:
        # The local workers share this machine's cores rather than each taking them all.
        threads = max(1, (os.cpu_count() or 1) // args.workers)
    if args.scheduler:
        try:
            client = Client(args.scheduler)
        except (OSError, ValueError) as e:
            sys.exit(f"error: no Dask scheduler at {args.scheduler}: {e}")
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    # Keys of this run's own: a scheduler runs a key once while its result is held, so two drivers sharing one
    # (two plans, two users) must not name their tasks alike.
    run = uuid.uuid4().hex
    try:
        futures = [
            client.submit(
                build_tile, tincull, plan, i, threads, key=f"tincull-tile-{i}-{run}", retries=args.retries, pure=False
            )
            for i in range(tiles)
        ]
        reports = []
        for k, fut in enumerate(as_completed(futures), 1):
            reports.append(fut.result())
            print(f"tiles: {k}/{tiles}", file=sys.stderr)
        merging = client.submit(merge, tincull, plan, out, futures, key=f"tincull-merge-{run}", pure=False)
        merged = merging.result()
    except RuntimeError as e:
        # A tile or the merge failed (after its retries): tincull's own message, without a traceback.
        sys.exit(f"error: {e}")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    summary = {
        "tiles": tiles,
        "seconds": time.time() - start,
        "tile_peak_memory_bytes": max((r.get("peak_memory_bytes") or 0) for r in reports),
        "merge": merged,
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
