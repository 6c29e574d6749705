#!/usr/bin/env python3
"""Speed-up of `tetiso run` against the number of working MPI processes, for
the paper's three series (250, 125 and 63 domains), in the style of its
Fig. 11. Writes NAME.csv, NAME.png and NAME.json (command, machine, commit).

    scripts/sweep_speedup.py --lattice 100 --workers 1,2 --out results/speedup/local

P workers run as `mpirun -np P+1` (rank 0 controls). Each point is the
median of --repeat runs of the job's own clock (report's seconds.job: the
tasks, domain generation included, without MPI start-up). Speed-up is T(1)/T(P)
within a series.
"""
import argparse
import csv
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile


def machine():
    model = platform.processor()
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
            if line.startswith("Model name:"):
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    return {"cpu": model, "cores": os.cpu_count(), "host": platform.node()}


def commit():
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "unknown"


def run_once(args, domains, workers, scratch):
    report = os.path.join(scratch, "report.json")
    command = [args.mpirun, "--oversubscribe", "--bind-to", "none", "-np", str(workers + 1), args.tetiso, "run",
               "--lattice", str(args.lattice), "--domains", str(domains), "--field", args.field, "--quiet",
               "-o", os.path.join(scratch, "surface.ply"), "--report", report] + args.extra
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    subprocess.run(command, check=True, env=env)
    return json.load(open(report))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tetiso", default="build/core/tetiso")
    parser.add_argument("--mpirun", default="mpirun")
    parser.add_argument("--lattice", type=int, required=True)
    parser.add_argument("--series", default="250,125,63")
    parser.add_argument("--workers", required=True, help="comma-separated worker counts, 1 first")
    parser.add_argument("--field", default="paper")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--out", required=True, help="path prefix of the outputs")
    parser.add_argument("extra", nargs="*", help="more arguments for tetiso run (after --)")
    args = parser.parse_args()
    series = [int(d) for d in args.series.split(",")]
    workers = [int(p) for p in args.workers.split(",")]
    if workers[0] != 1:
        sys.exit("the worker counts must start with 1: speed-up is relative to one worker")

    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for domains in series:
            base = None
            for p in workers:
                reports = [run_once(args, domains, p, scratch) for _ in range(args.repeat)]
                seconds = statistics.median(r["seconds"]["job"] for r in reports)
                base = base or seconds
                rows.append({"domains": domains, "workers": p, "seconds": round(seconds, 4),
                             "speedup": round(base / seconds, 3), "efficiency": round(base / seconds / p, 3),
                             "raw_triangles": reports[0]["raw_triangles"], "triangles": reports[0]["triangles"]})
                print(f"D={domains:4d} P={p:3d}  {seconds:8.3f} s  speed-up {base / seconds:6.2f}", flush=True)

    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out + ".csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    meta = {"command": " ".join([os.path.relpath(sys.argv[0])] + sys.argv[1:]), "machine": machine(),
            "commit": commit(), "lattice": args.lattice, "field": args.field, "repeat": args.repeat}
    with open(args.out + ".json", "w") as f:
        json.dump(meta, f, indent=2)

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot([1, max(workers)], [1, max(workers)], "k--", linewidth=1, label="ideal")
    for domains, marker in zip(series, "osd^v"):
        points = [(r["workers"], r["speedup"]) for r in rows if r["domains"] == domains]
        ax.plot(*zip(*points), marker=marker, label=f"{domains} domains")
    ax.set_xlabel("working MPI processes")
    ax.set_ylabel("speed-up")
    ax.set_title(f"tetiso run, N = {args.lattice}, {meta['machine']['cores']} cores, {meta['commit']}")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out + ".png", dpi=120)


if __name__ == "__main__":
    main()
