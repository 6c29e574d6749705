#!/usr/bin/python3
"""The per-call cost of `import tetiso` on small inputs: how long a call
takes from Python, against the binding's floor (an attribute, a view) and
against running the `tetiso` command for the same work. Writes
results/python-binding/runs.json and renders the page.

    PYTHONPATH=build/python tools/bench_python.py [--build build] [--batches 15]

Each case runs in batches of calls sized to take about 0.2 s; a batch's time
over its calls is one sample; the page gives the median and the fastest of
the batches. Debian's python3 with NumPy; the build's module and command.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "python" / "tests"))
from bench_meta import machine_facts  # noqa: E402
from vtu_fixture import read_ascii_vtu  # noqa: E402

import tetiso  # noqa: E402


def samples(call, batches):
    """Seconds per call: one sample per batch, batches sized to about 0.2 s."""
    start = time.perf_counter()
    call()
    once = max(time.perf_counter() - start, 1e-7)
    per_batch = max(1, min(100_000, int(0.2 / once)))
    out = []
    for _ in range(batches):
        start = time.perf_counter_ns()
        for _ in range(per_batch):
            call()
        out.append((time.perf_counter_ns() - start) / per_batch / 1e9)
    return per_batch, out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default=str(ROOT / "build"))
    parser.add_argument("--batches", type=int, default=15)
    args = parser.parse_args()
    cli = pathlib.Path(args.build) / "core" / "tetiso"
    fixture = ROOT / "meshes" / "solver" / "cube-ascii.vtu"
    points, tets, distance = read_ascii_vtu(fixture, "distance")
    one_points = points[[0, 1, 7, 49]]
    one_tet = np.array([[0, 1, 2, 3]])
    one_field = np.array([0.0, 1.0, 1.0, 1.0])
    raw = tetiso.extract(points, tets, distance, 2.1)
    tiny = tetiso.extract(one_points, one_tet, one_field, 0.5)

    cases = [
        ("attribute", "`surface.vertex_count`: a call into the module and back", lambda: tiny.vertex_count),
        ("view", "`surface.x`: a read-only NumPy view of the surface's own memory", lambda: tiny.x),
        ("extract-1", "`extract` of one tetrahedron (4 nodes) given as arrays",
         lambda: tetiso.extract(one_points, one_tet, one_field, 0.5)),
        ("extract-fixture", f"`extract` of meshes/solver/cube-ascii.vtu as arrays ({len(points)} nodes, "
         f"{len(tets):,} tetrahedra; {raw.triangle_count} triangles)",
         lambda: tetiso.extract(points, tets, distance, 2.1)),
        ("reduce-fixture", f"`reduce` of that surface ({raw.triangle_count} triangles)", lambda: tetiso.reduce(raw)),
        ("check-fixture", "`check` of that surface, without self-intersections",
         lambda: tetiso.check(raw, self_intersections=False)),
        ("lattice-8", "`extract_lattice(8)`: the paper's field on 8³ nodes", lambda: tetiso.extract_lattice(8)),
    ]
    results = []
    for name, label, call in cases:
        calls, seconds = samples(call, args.batches)
        results.append({"name": name, "label": label, "calls_per_batch": calls, "seconds": seconds})
        print(f"{name}: median {statistics.median(seconds) * 1e6:.2f} µs", file=sys.stderr)

    # The same work as a command: a process started, the file read, the surface written.
    with tempfile.TemporaryDirectory() as scratch:
        command = [str(cli), "extract", "--lattice", "8", "-o", os.path.join(scratch, "s.ply")]
        seconds = []
        for _ in range(args.batches):
            start = time.perf_counter_ns()
            subprocess.run(command, check=True, capture_output=True)
            seconds.append((time.perf_counter_ns() - start) / 1e9)
        results.append({"name": "cli-lattice-8", "label": "`tetiso extract --lattice 8 -o s.ply`, the command run "
                        "from Python (subprocess)", "calls_per_batch": 1, "seconds": seconds})

    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    data = {
        "command": "PYTHONPATH=build/python tools/bench_python.py --batches " + str(args.batches),
        "commit": commit + (" (with uncommitted changes)" if dirty else ""),
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "load_before": os.getloadavg()[0],
        "machine": machine_facts(),
        "cases": results,
    }
    out = ROOT / "results" / "python-binding"
    out.mkdir(parents=True, exist_ok=True)
    (out / "runs.json").write_text(json.dumps(data, indent=1) + "\n")
    subprocess.run([sys.executable, str(ROOT / "tools" / "render_results.py"), "python-binding"], check=True)


if __name__ == "__main__":
    main()
