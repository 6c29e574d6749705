#!/usr/bin/env python3
"""Speed-up of `tetiso run` against the number of working MPI processes, for
the paper's three series (250, 125 and 63 domains), in the style of its
Fig. 11. Writes NAME.csv (one row per series and worker count), NAME.png
(speed-up against working processes, with the ideal line) and NAME.json
(command, machine, commit, and every run's report with each rank's peak
memory).

    tools/sweep_speedup.py --lattice 100 --workers 1,2 --out out/local

P workers run as `mpirun -np P+1` (rank 0 controls and holds the pieces, the
P others run tasks). Each point is the median of --repeat runs of the job's
own clock (report's seconds.job: every task, domain generation included,
without MPI start-up and without writing the surface). Speed-up is T(1)/T(P)
within a series, efficiency is speed-up / P. The CSV also gives the median of
seconds.total (MPI start-up and writing the surface included) and the wall
time of the whole mpirun, and the largest peak resident memory of any worker
and of rank 0 (each rank runs under tools/rank_peak_rss.py).

A long sweep can be split over several calls (a lent machine runs one
command for at most minutes): --points runs chosen (domains:workers) pairs,
--deadline stops starting runs that would not finish in time, the outputs are
rewritten after every run (a run with nothing to estimate it from, the
first of a sweep, always starts), a failed run drops the rest of its series
(the output, and so the failure, does not depend on the worker count), and
--merge combines the runs of earlier NAME.json files into one table and plot:

    tools/sweep_speedup.py --lattice 500 --points 125:1,125:15 --deadline 500 --out part1
    tools/sweep_speedup.py --merge part1.json part2.json --out out/device
"""
import argparse
import csv
import hashlib
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def machine():
    info = {"cpu": platform.processor(), "cores": os.cpu_count(), "host": platform.node(),
            "kernel": platform.release()}
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        fields = {}
        for line in lscpu.splitlines():
            if ":" in line:
                key, value = line.split(":", 1)
                fields[key.strip()] = value.strip()
        info["cpu"] = fields.get("Model name", info["cpu"])
        for key in ("Thread(s) per core", "Core(s) per socket", "Socket(s)", "NUMA node(s)", "L3 cache"):
            if key in fields:
                info[key] = fields[key]
    except OSError:
        pass
    try:
        with open("/proc/meminfo") as f:
            info["memory_gib"] = round(int(f.readline().split()[1]) / 2**20, 1)
    except OSError:
        pass
    return info


def commit(given):
    if given:
        return given
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=HERE).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, cwd=HERE).stdout.strip()
        return (head + ("+dirty" if dirty else "")) if head else "unknown"
    except OSError:
        return "unknown"


def run_once(args, domains, workers, scratch):
    report = os.path.join(scratch, "report.json")
    rss_log = os.path.join(scratch, "rss.jsonl")
    perf_log = os.path.join(scratch, "perf.csv")
    surface = os.path.join(scratch, "surface" + args.format)
    for stale in (report, rss_log, perf_log):
        if os.path.exists(stale):
            os.remove(stale)
    # Counted system-wide (-a): the ranks are separate processes started by mpirun.
    perf = (["perf", "stat", "-a", "-x", ",", "-e", args.perf_events, "-o", perf_log]
            if args.perf_events else [])
    command = (perf + [args.mpirun, "--oversubscribe", "--bind-to", args.bind, "-np", str(workers + 1),
                sys.executable, os.path.join(HERE, "rank_peak_rss.py"), args.tetiso, "run",
                "--lattice", str(args.lattice), "--domains", str(domains), "--field", args.field, "--quiet",
                "-o", surface, "--report", report] + args.extra)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               TETISO_RSS_LOG=rss_log)
    started = time.perf_counter()
    subprocess.run(command, check=True, env=env)
    wall = time.perf_counter() - started
    with open(report) as f:
        result = json.load(f)
    with open(rss_log) as f:
        ranks = sorted((json.loads(line) for line in f), key=lambda r: r["rank"])
    if len(ranks) != workers + 1:
        sys.exit(f"expected {workers + 1} ranks' memory records, got {len(ranks)}")
    result["wall_seconds"] = wall
    result["peak_rss_kib"] = [r["peak_rss_kib"] for r in ranks]
    result["bind"] = args.bind
    with open(surface, "rb") as f:
        result["surface_sha256"] = hashlib.sha256(f.read()).hexdigest()
    if args.keep_surfaces:
        # One file per series: the surface does not depend on the worker count
        # (the hashes above show it), so the last run's stands for all.
        os.makedirs(args.keep_surfaces, exist_ok=True)
        shutil.copyfile(surface, os.path.join(args.keep_surfaces, f"surface-d{domains}{args.format}"))
    if perf:
        result["perf"] = read_perf(perf_log)
    return result


def read_perf(path):
    """perf stat -x , lines: value,unit,event,... ; uncounted events are left out."""
    counts = {}
    with open(path) as f:
        for line in f:
            fields = line.strip().split(",")
            if len(fields) >= 3 and not line.startswith("#"):
                try:
                    counts[fields[2]] = float(fields[0])
                except ValueError:
                    pass  # "<not supported>" or "<not counted>"
    return counts


def median_or_blank(values, digits):
    return round(statistics.median(values), digits) if values else ""


def max_or_blank(values, digits):
    return round(max(values), digits) if values else ""


def points(runs):
    """(domains, workers, reports, median job seconds, the series' median at
    one worker or None) per point, in series order (most domains first)."""
    groups = {}
    for run in runs:
        groups.setdefault((run["domains"], run["workers"]), []).append(run["report"])
    base = {d: statistics.median(r["seconds"]["job"] for r in reports)
            for (d, p), reports in groups.items() if p == 1}
    return [(domains, p, reports, statistics.median(r["seconds"]["job"] for r in reports), base.get(domains))
            for (domains, p), reports in sorted(groups.items(), key=lambda item: (-item[0][0], item[0][1]))]


def table(runs):
    """One row per (domains, workers), in series order (most domains first)."""
    rows = []
    for domains, p, reports, seconds, t1 in points(runs):
        rows.append({
            "domains": domains, "workers": p, "runs": len(reports), "seconds": round(seconds, 3),
            "speedup": round(t1 / seconds, 3) if t1 else "",
            "efficiency": round(t1 / seconds / p, 3) if t1 else "",
            "total_seconds": round(statistics.median(r["seconds"]["total"] for r in reports), 3),
            # A run made outside the sweep (a command cut near a lent machine's
            # limit, say) may lack the wall time and the per-rank memory.
            "wall_seconds": median_or_blank([r["wall_seconds"] for r in reports if "wall_seconds" in r], 3),
            "task_seconds": round(statistics.median(sum(t["end"] - t["start"] for t in r["tasks"])
                                                    for r in reports), 3),
            "worker_peak_rss_mib": max_or_blank([max(r["peak_rss_kib"][1:]) / 1024 for r in reports
                                                 if r.get("peak_rss_kib")], 1),
            "rank0_peak_rss_mib": max_or_blank([r["peak_rss_kib"][0] / 1024 for r in reports
                                                if r.get("peak_rss_kib")], 1),
            "raw_triangles": reports[0]["raw_triangles"], "triangles": reports[0]["triangles"]})
    return rows


def plot(rows, title, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot", file=sys.stderr)
        return
    rows = [r for r in rows if r["speedup"] != ""]
    if not rows:
        return
    top = max(r["workers"] for r in rows)
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot([0, top + 1], [0, top + 1], "k--", linewidth=1, label="ideal")
    series = sorted({r["domains"] for r in rows}, reverse=True)
    for domains, marker in zip(series, "osd^v"):
        points = [(r["workers"], r["speedup"]) for r in rows if r["domains"] == domains]
        ax.plot(*zip(*points), marker=marker, label=f"{domains} domains")
    ax.set_xlabel("working MPI processes")
    ax.set_ylabel("speed-up")
    ax.set_xlim(0, top + 1)
    ax.set_ylim(0, top + 1)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def write(out, meta, runs):
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    rows = table(runs)
    if rows:
        with open(out + ".csv", "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    with open(out + ".json", "w") as f:
        # One line per run: the task records make the bulk of the file.
        f.write(json.dumps(meta, indent=1)[:-2] + ',\n "runs": [\n')
        f.write(",\n".join(json.dumps(run, separators=(",", ":")) for run in runs))
        f.write("\n ]\n}\n")
    return rows


def title(meta):
    m = meta["machine"]
    return (f"tetiso run, N = {meta['lattice']}, paper field, {m['cores']} cores ({m['cpu']}), "
            f"commit {meta['commit']}")


def merged(paths, command):
    """The runs of several outputs of this script, and one meta naming them
    (each part's own meta, its date and command included, under "sources")."""
    runs, sources = [], []
    for path in paths:
        with open(path) as f:
            part = json.load(f)
        runs += part.pop("runs")
        # A merged part names its own sources: keep those, which carry the dates.
        sources += part["sources"] if part.get("sources") else [dict(part, file=os.path.basename(path))]
    lattices = {s["lattice"] for s in sources}
    if len(lattices) != 1:
        sys.exit(f"the files are for different lattices: {sorted(lattices)}")
    commits = sorted({s["commit"] for s in sources})
    meta = {"command": command, "lattice": lattices.pop(), "commit": ",".join(commits),
            "machine": sources[0]["machine"], "sources": sources}
    return meta, runs


def merge(args):
    meta, runs = merged(args.merge, " ".join([os.path.relpath(sys.argv[0])] + sys.argv[1:]))
    rows = write(args.out, meta, runs)
    plot(rows, title(meta), args.out + ".png")


def estimate(runs, domains, workers):
    """Seconds a run should take, from earlier runs of the same series: from
    more workers, P_known/P times as long (an upper bound while speed-up is at
    most linear); from fewer, 15% over linear scaling; else 15% over another
    series with as many workers. None if nothing is known."""
    known = [r["report"]["wall_seconds"] * r["workers"] / workers * (1.15 if r["workers"] < workers else 1.0)
             for r in runs if r["domains"] == domains]
    if not known:
        # A series not yet run does about the same work as the others.
        known = [r["report"]["wall_seconds"] * 1.15 for r in runs if r["workers"] == workers]
    return min(known) if known else None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tetiso", default="build/core/tetiso")
    parser.add_argument("--mpirun", default="mpirun")
    parser.add_argument("--bind", default="none", help="mpirun --bind-to (none, core, ...)")
    parser.add_argument("--lattice", type=int)
    parser.add_argument("--series", default="250,125,63")
    parser.add_argument("--workers", help="comma-separated worker counts, 1 first")
    parser.add_argument("--points", help="instead of --series x --workers: DOMAINS:WORKERS,... in this order")
    parser.add_argument("--field", default="paper")
    parser.add_argument("--format", default=".ply", choices=[".ply", ".vtp"], help="surface written by each run")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--deadline", type=float, help="seconds: start no run expected to end after this")
    parser.add_argument("--commit", help="commit to record (default: git's HEAD, +dirty if modified)")
    parser.add_argument("--prior", nargs="+", default=[], metavar="JSON",
                        help="earlier outputs whose runs inform --deadline's estimates (not the table)")
    parser.add_argument("--keep-surfaces", metavar="DIR", help="copy each series' surface to DIR/surface-dD.EXT")
    parser.add_argument("--perf-events", metavar="LIST",
                        help="run each job under perf stat -a -e LIST and record the counts (perf must work here)")
    parser.add_argument("--merge", nargs="+", metavar="JSON", help="combine the runs of earlier outputs, run nothing")
    parser.add_argument("--out", required=True, help="path prefix of the outputs")
    parser.add_argument("extra", nargs="*", help="more arguments for tetiso run (after --)")
    args = parser.parse_args()
    if args.merge:
        return merge(args)
    if not args.lattice:
        sys.exit("--lattice is required")
    if args.points:
        points = [tuple(int(v) for v in p.split(":")) for p in args.points.split(",")]
    elif args.workers:
        workers = [int(p) for p in args.workers.split(",")]
        if workers[0] != 1:
            sys.exit("the worker counts must start with 1: speed-up is relative to one worker")
        points = [(int(d), p) for d in args.series.split(",") for p in workers]
    else:
        sys.exit("--workers or --points is required")
    if not os.access(args.tetiso, os.X_OK):
        sys.exit(f"{args.tetiso}: no such program (build first, or pass --tetiso)")

    started = time.perf_counter()
    meta = {"command": " ".join([os.path.relpath(sys.argv[0])] + sys.argv[1:]), "machine": machine(),
            "commit": commit(args.commit), "lattice": args.lattice, "field": args.field, "bind": args.bind,
            "repeat": args.repeat, "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "load_average_before": os.getloadavg(), "skipped": [], "failed": []}
    runs, prior, failed = [], [], set()
    for path in args.prior:
        if os.path.exists(path):
            with open(path) as f:
                prior += [r for r in json.load(f)["runs"] if r["report"]["lattice"] == args.lattice]
    with tempfile.TemporaryDirectory() as scratch:
        for domains, p in points:
            if domains in failed:
                continue
            for _ in range(args.repeat):
                guess = estimate(prior + runs, domains, p)
                if args.deadline and guess and time.perf_counter() - started + guess > args.deadline:
                    meta["skipped"].append(f"{domains}:{p}")
                    print(f"D={domains:4d} P={p:3d}  skipped: ~{guess:.0f} s would pass the deadline", flush=True)
                    break
                try:
                    report = run_once(args, domains, p, scratch)
                except subprocess.CalledProcessError as e:
                    # The output does not depend on the worker count: a series
                    # whose run failed would fail again, so it is dropped.
                    meta["failed"].append({"point": f"{domains}:{p}", "status": e.returncode})
                    failed.add(domains)
                    print(f"D={domains:4d} P={p:3d}  FAILED (status {e.returncode}): series dropped", flush=True)
                    write(args.out, meta, runs)
                    break
                runs.append({"domains": domains, "workers": p, "report": report})
                print(f"D={domains:4d} P={p:3d}  job {report['seconds']['job']:8.3f} s  "
                      f"wall {report['wall_seconds']:8.3f} s  "
                      f"worker peak {max(report['peak_rss_kib'][1:]) / 1024:8.1f} MiB  "
                      f"rank 0 peak {report['peak_rss_kib'][0] / 1024:8.1f} MiB", flush=True)
                meta["load_average_after"] = os.getloadavg()
                write(args.out, meta, runs)  # after every run: a killed sweep keeps what it measured
    rows = write(args.out, meta, runs)
    for r in rows:
        print(f"D={r['domains']:4d} P={r['workers']:3d}  {r['seconds']:8.3f} s  speed-up {r['speedup']}")
    plot(rows, title(meta), args.out + ".png")


if __name__ == "__main__":
    main()
