#!/usr/bin/env python3
"""Why a job's tasks run slower when every core is busy.

When P workers keep every core busy, the tasks of `tetiso run` can take
longer in sum than the same tasks run by one worker, and that alone caps the
speed-up below P. This probe separates the candidate causes by running one
single-thread command alone on one core, then as P pinned copies at once, and
comparing the medians:

  compute   a shell loop with no memory traffic: a ratio above 1 means the
            cores clock down when all are busy;
  small     `tetiso reduce` of a surface small enough for a core's L2 cache
            (lattice 24 gyroid), run 40 times per copy;
  domain    `tetiso reduce` of a domain-sized surface (lattice 80 gyroid,
            about the 350,000 triangles of one of 125 domains at N = 500):
            its working set (about 120 MB) fits the shared L3 cache alone,
            not as P copies; per-step medians come from the reports.

    scripts/probe_contention.py --tetiso build/core/tetiso --cores 1-15 --out out/contention
    scripts/probe_contention.py --probes domain --cores 1-15 --out /tmp/domain-only

Writes OUT.json (every run's seconds, the domain reports' steps, the ratios)
and prints one line per probe. Needs `taskset` (util-linux).
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time


def parse_cores(text):
    cores = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        cores += range(int(lo), int(hi or lo) + 1)
    return cores


def run_pinned(cores, argv_for):
    """Starts argv_for(i) on cores[i] for every i at once; returns each wall time."""
    starts, procs = [], []
    for i, core in enumerate(cores):
        starts.append(time.perf_counter())
        procs.append(subprocess.Popen(["taskset", "-c", str(core)] + argv_for(i),
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE))
    ends = [None] * len(procs)
    while any(e is None for e in ends):
        for i, p in enumerate(procs):
            if ends[i] is None and p.poll() is not None:
                ends[i] = time.perf_counter()
                if p.returncode != 0:
                    for other in procs:
                        if other.poll() is None:
                            other.kill()
                            other.wait()
                    sys.exit(f"probe_contention: {' '.join(p.args)} failed: {p.stderr.read().decode().strip()}")
        time.sleep(0.002)
    return [e - s for s, e in zip(starts, ends)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tetiso", default="build/core/tetiso")
    ap.add_argument("--cores", default="1-15", help="cores of the copies run at once (the lone run uses the first)")
    ap.add_argument("--repeat", type=int, default=3, help="lone runs; the copies run at once repeat max(1, REPEAT-1) times")
    ap.add_argument("--probes", default="compute,small,domain", help="which probes to run, comma-separated")
    ap.add_argument("--out", required=True, help="OUT.json is written")
    args = ap.parse_args()
    cores = parse_cores(args.cores)
    wanted = args.probes.split(",")
    unknown = [name for name in wanted if name not in ("compute", "small", "domain")]
    if unknown:
        sys.exit(f"probe_contention: unknown probe(s) {', '.join(unknown)}; known: compute, small, domain")
    tetiso = os.path.abspath(args.tetiso)
    if not os.access(tetiso, os.X_OK):
        sys.exit(f"probe_contention: {args.tetiso} is not an executable tetiso (build it, or pass --tetiso)")
    if shutil.which("taskset") is None:
        sys.exit("probe_contention: taskset (util-linux) is needed to pin the copies to cores")

    with tempfile.TemporaryDirectory(prefix="tetiso-contention-") as tmp:
        for lattice in (24, 80):
            subprocess.run([tetiso, "extract", "--lattice", str(lattice), "--field", "gyroid", "-o",
                            f"{tmp}/g{lattice}.ply"], check=True, stdout=subprocess.DEVNULL)
        probes = {
            "compute": lambda i: ["bash", "-c", "for ((i = 0; i < 1500000; i++)); do :; done"],
            "small": lambda i: ["bash", "-c", f"for k in $(seq 40); do {tetiso} reduce {tmp}/g24.ply -o {tmp}/s{i}.ply "
                                              "--max-error 0.04 --threads 1 >/dev/null || exit 1; done"],
            "domain": lambda i: [tetiso, "reduce", f"{tmp}/g80.ply", "-o", f"{tmp}/d{i}.ply", "--max-error", "0.0125",
                                 "--threads", "1", "--report", f"{tmp}/d{i}.json"],
        }
        result = {"cores": cores, "tetiso": args.tetiso, "probes": {}}
        for name in wanted:
            argv_for = probes[name]
            entry = {"alone_s": [], "together_s": []}
            steps = {"alone": [], "together": []}
            for _ in range(args.repeat):
                entry["alone_s"] += run_pinned(cores[:1], argv_for)
                if name == "domain":
                    steps["alone"].append(json.load(open(f"{tmp}/d0.json"))["stage_seconds"])
            for _ in range(max(1, args.repeat - 1)):
                entry["together_s"] += run_pinned(cores, argv_for)
                if name == "domain":
                    steps["together"] += [json.load(open(f"{tmp}/d{i}.json"))["stage_seconds"] for i in range(len(cores))]
            alone, together = statistics.median(entry["alone_s"]), statistics.median(entry["together_s"])
            entry["ratio_of_medians"] = together / alone
            line = f"{name:7s} alone {alone:7.3f} s   {len(cores)} at once {together:7.3f} s   ratio {together / alone:.3f}"
            if name == "domain":
                entry["step_medians"] = {
                    when: {k: statistics.median(s[k] for s in runs) for k in runs[0]} for when, runs in steps.items()}
                ratios = {k: entry["step_medians"]["together"][k] / entry["step_medians"]["alone"][k]
                          for k in entry["step_medians"]["alone"] if entry["step_medians"]["alone"][k] > 0}
                entry["step_ratios"] = ratios
                line += "   steps: " + ", ".join(f"{k} {v:.2f}" for k, v in ratios.items())
            result["probes"][name] = entry
            print(line, flush=True)
    with open(args.out + ".json", "w") as f:
        json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
