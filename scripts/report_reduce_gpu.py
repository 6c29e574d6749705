#!/usr/bin/env python3
"""Turns the GPU reduction's measurements into results/reduce-gpu/README.md.

Usage: report_reduce_gpu.py [DIR]   (default results/reduce-gpu)

Reads, from DIR, what `scripts/gpu_check.sh bench OUT COMMIT` wrote on the
device machine:
  bench_reduce_gpu.json  Google Benchmark JSON of bench/bench_reduce_gpu.cpp
                         (aggregates of repetitions)
  rounds_n100.json       `tetiso reduce --device gpu --report` of the N = 100
                         paper surface: every round's size and seconds
  profile_n100.txt       the same reduction under TETISO_GPU_PROFILE: seconds
                         by call site of the round driver
  meta.json              commands, commit, GPU, host, date
and writes README.md and rounds.png there. Debian's python3 with
python3-matplotlib.
"""
import json
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import load_aggregates, table  # noqa: E402

TARGET_RATE = 50e6          # input triangles/s on one GPU, N = 100 surface on the device
TARGET_DOMAIN_SECONDS = 0.015  # one 10^6-node domain task, nothing to reduced piece in host memory
# The least a round must move through device memory, per triangle at the
# round's start: positions and triangles read; fans (face, next, prev per
# corner), edges (two ends and a slot), face records (32 B), cones (16 B a
# vertex), the operations' kind, priority, position, bound and survivor (per
# edge), the order and reservations of the selection, and the compacted
# surface written once each. About 1.5 edges and 0.5 vertices a triangle.
BYTES_PER_TRIANGLE_ROUND = 12 + 6 + 36 + 18 + 32 + 8 + 37 + 12 + 24 + 16

NAME = r"^(?P<case>reduce/(?P<who>gpu|tetiso|meshopt)/N:(?P<n>\d+)(/threads:(?P<threads>\d+))?|domain/(?P<dwho>gpu|tetiso)/N:(?P<dn>\d+)/D:(?P<dd>\d+)|copy/gpu)(/repeats:\d+)?(/manual_time|/real_time)?$"


def key(match):
    if match["who"]:
        return ("reduce", match["who"], int(match["n"]), int(match["threads"] or 0))
    if match["dwho"]:
        return ("domain", match["dwho"], int(match["dn"]), int(match["dd"]))
    return ("copy", "gpu", 0, 0)


def fmt_ms(seconds):
    return f"{seconds * 1e3:,.1f}" if seconds < 10 else f"{seconds * 1e3:,.0f}"


# The backend's primitives that read a value back (a size, a count), each
# waiting for the device, and those that only launch work.
READS_BACK = ("get", "count", "exclusive_scan", "filter", "rank", "copy_if")
LAUNCHES = ("for_each", "for_each_of", "assign", "set")


def profile_rows(path, top=10):
    """(milliseconds, calls, site) of the profile's heaviest call sites, and its total."""
    total, rows = None, []
    for line in path.read_text().splitlines():
        m = re.match(r"tetiso GPU profile: ([\d.]+) s", line)
        if m:
            total = float(m.group(1))
        m = re.match(r"\s+([\d.]+) ms\s+(\d+) calls\s+(\S+) (\S+)$", line)
        if m:
            rows.append((float(m.group(1)), int(m.group(2)), f"{m.group(3)} at {m.group(4)}"))
    return total, rows[:top]


def shown(command):
    """A command as run on the device machine, its output folder named OUT."""
    return re.sub(r"/\S*/(?=[a-z_0-9]+\.json)", "OUT/", command)


def main(argv):
    out = Path(argv[1] if len(argv) > 1 else "results/reduce-gpu")
    meta = json.loads((out / "meta.json").read_text())
    context, cases = load_aggregates(out / "bench_reduce_gpu.json", NAME, key)
    rounds = json.loads((out / "rounds_n100.json").read_text())

    def case(*k):
        return cases.get(k)

    n = 100
    gpu = case("reduce", "gpu", n, 0)
    cpu1 = case("reduce", "tetiso", n, 1)
    cpu_all = max((k for k in cases if k[:3] == ("reduce", "tetiso", n) and k[3] > 1), default=None)
    cpu_all = cases.get(cpu_all) if cpu_all else None
    all_threads = max(k[3] for k in cases if k[:3] == ("reduce", "tetiso", n))
    meshopt = case("reduce", "meshopt", n, 1) or case("reduce", "meshopt", n, 0)
    dgpu = next((v for k, v in cases.items() if k[:2] == ("domain", "gpu")), None)
    dcpu = next((v for k, v in cases.items() if k[:2] == ("domain", "tetiso")), None)
    dkey = next((k for k in cases if k[:2] == ("domain", "gpu")), None)
    copy = case("copy", "gpu", 0, 0)

    triangles_in = gpu["median"]["triangles_in"]
    triangles_out = gpu["median"]["triangles_out"]
    gpu_s = gpu["time_ms"] / 1e3
    rate = triangles_in / gpu_s
    bandwidth = copy["median"]["GB/s"] * 1e9 if copy else float("nan")
    round_rows = rounds["rounds"]
    triangle_rounds = sum(r["triangles"] for r in round_rows)
    floor_bytes = triangle_rounds * BYTES_PER_TRIANGLE_ROUND
    floor_s = floor_bytes / bandwidth
    # Rounds with almost nothing to test: what a round costs whatever its work.
    tail = [r["seconds"] for r in round_rows if r["candidates"] < 5000]
    fixed = sorted(tail)[len(tail) // 2] if tail else float("nan")

    lines = [
        "# Reduction on the GPU: one NVIDIA GPU against its host's CPU cores",
        "",
        f"The paper's test surface at N = {n} (1 domain; field 2cos(10x)+2sin(10y)+cos(10z) at level 0.5), "
        "reduced at the job's default bound (0.25 lattice spacings) by `tetiso::Gpu::reduce` and by the CPU's "
        "`tetiso::reduce` on the same host, with meshoptimizer beside them; and one domain task of the "
        "N = 500, 125-domain job (a 10⁶-node lattice box, from nothing to its reduced piece with its samples in "
        "host memory) on the GPU and on one CPU core. **Before any timing, every GPU case's piece is checked "
        "against the CPU's, byte for byte** (positions, keys, flags, triangles, error bounds, samples).",
        "",
        f"GPU: {meta.get('gpu', '?')}. Host: {meta['cpu_model']}, {meta['cpus']} CPUs.",
        "",
        "## Figures",
        "",
        "Medians of 5 repetitions. The GPU reduction is timed from the surface on the device to the reduced "
        "surface on the device (upload and download apart); the domain tasks and the CPU cases by wall clock.",
        "",
    ]
    rows = [["tetiso, GPU", "1 GPU", fmt_ms(gpu_s), fmt_ms(gpu["min_ms"] / 1e3), f"{rate / 1e6:.2f}", "1.00×"]]
    for label, c, threads in (("tetiso, CPU", cpu1, "1 thread"), ("tetiso, CPU", cpu_all, f"{all_threads} threads"),
                              ("meshoptimizer (no topology kept)", meshopt, "1 thread")):
        if c:
            rows.append([label, threads, fmt_ms(c["time_ms"] / 1e3), fmt_ms(c["min_ms"] / 1e3),
                         f"{triangles_in / (c['time_ms'] / 1e3) / 1e6:.2f}", f"{c['time_ms'] / 1e3 / gpu_s:.1f}×"])
    lines += [f"**N = {n} reduction**: {triangles_in:,.0f} → {triangles_out:,.0f} triangles in "
              f"{len(round_rows)} rounds; upload {gpu['median'].get('upload_s', 0) * 1e3:.1f} ms, download "
              f"{gpu['median'].get('download_s', 0) * 1e3:.1f} ms; "
              f"{gpu['median'].get('device_MiB', 0):,.0f} MiB of device memory held.", "",
              table(["", "where", "median ms", "fastest ms", "M input triangles/s", "time / GPU's"], rows), ""]
    if dgpu and dcpu:
        d_gpu_s, d_cpu_s = dgpu["time_ms"] / 1e3, dcpu["time_ms"] / 1e3
        lines += [f"**Domain task** (N = {dkey[2]}, {dkey[3]} domains, the middle one: "
                  f"{dgpu['median']['nodes']:,.0f} nodes, {dgpu['median']['triangles_out']:,.0f} triangles out):", "",
                  table(["", "where", "median ms", "fastest ms", "time / GPU's"],
                        [["tetiso, GPU", "1 GPU", fmt_ms(d_gpu_s), fmt_ms(dgpu["min_ms"] / 1e3), "1.00×"],
                         ["tetiso, CPU", "1 core", fmt_ms(d_cpu_s), fmt_ms(dcpu["min_ms"] / 1e3),
                          f"{d_cpu_s / d_gpu_s:.1f}×"]]), "",
                  f"Of the GPU's task, extraction took {dgpu['median']['extract_s'] * 1e3:.2f} ms and reduction "
                  f"{dgpu['median']['reduce_s'] * 1e3:.1f} ms.", ""]

    lines += ["## Targets", ""]
    met = rate >= TARGET_RATE
    lines.append(f"- **≥ {TARGET_RATE / 1e6:.0f} M input triangles/s on one GPU** (N = {n}, ≤ "
                 f"{triangles_in / TARGET_RATE * 1e3:.0f} ms): **{'met' if met else 'missed'}**, {rate / 1e6:.2f} M/s "
                 f"({fmt_ms(gpu_s)} ms, {gpu_s / (triangles_in / TARGET_RATE):.1f}× the target time), with the CPU's exact output.")
    if dgpu:
        d_gpu_s = dgpu["time_ms"] / 1e3
        lines.append(f"- **Domain task ≤ {TARGET_DOMAIN_SECONDS * 1e3:.0f} ms**: "
                     f"**{'met' if d_gpu_s <= TARGET_DOMAIN_SECONDS else 'missed'}**, {fmt_ms(d_gpu_s)} ms "
                     f"({d_gpu_s / TARGET_DOMAIN_SECONDS:.1f}× the target).")
    lines += ["- The targets were stated for an H100; this GPU has the same multiprocessors and more memory "
              "bandwidth.", ""]

    total, prof = profile_rows(out / "profile_n100.txt", top=1000)
    per_round_reads = sum(c for _, c, site in prof if site.split(" ")[0] in READS_BACK) / len(round_rows)
    per_round_launches = sum(c for _, c, site in prof if site.split(" ")[0] in LAUNCHES) / len(round_rows)
    sorts = sum(ms for ms, _, site in prof if site.startswith(("order_by_priority", "group_by_key")))
    lines += ["## Where the time goes", "",
              f"![time per round](rounds.png)", "",
              f"- **Memory bandwidth is not the limit.** A device-to-device copy moves "
              f"{bandwidth / 1e12:.2f} TB/s here (bytes read plus written). The rounds see {triangle_rounds:,} "
              f"triangles in all ({triangle_rounds / triangles_in:.1f}× the input); at about "
              f"{BYTES_PER_TRIANGLE_ROUND} bytes a triangle and round (every array of a round written once and "
              f"read once) that is {floor_bytes / 1e9:.2f} GB, {floor_s * 1e3:.2f} ms at that bandwidth: the "
              f"reduction takes {gpu_s / floor_s:.0f}× as long.",
              f"- **Each round costs at least about {fixed * 1e3:.1f} ms** (the median of the rounds with fewer "
              f"than 5,000 candidates): about {per_round_launches:.0f} launches besides those of CUB's sorts and scans, "
              f"{per_round_reads:.0f} reads by the host of a value it needs (a list's length, the end of the "
              f"selection), each waiting for the device, and the latency of the "
              f"round's slowest legality test, one thread's serial work. {len(round_rows)} rounds make "
              f"{len(round_rows) * fixed * 1e3:.0f} ms of it: with rounds as they are, the {triangles_in / TARGET_RATE * 1e3:.0f} ms "
              f"target needs fewer host reads (sizes kept on the device, rounds captured as graphs) as much as "
              f"faster tests.",
              "- **The rest is the legality tests**, run for every candidate of a round at once (speculation: the "
              "selection then waits only on legal operations): their work grows with the round's size, and the "
              "first rounds, with millions of candidates, take most of the time.",
              f"- **Sorts** (the priority order of the candidates and flips, the grouping of corners by vertex and "
              f"of samples by face) take {sorts:.1f} ms of the profile's {total * 1e3:.0f}.", ""]
    prof = prof[:10]
    if prof:
        lines += [f"By call site of the round driver (`TETISO_GPU_PROFILE=1`, which waits for the device around "
                  f"every primitive, so its {total:.3f} s add up to more than the plain run's), the heaviest:", "",
                  table(["ms", "calls", "primitive at"], [[f"{ms:.1f}", calls, f"`{site}`"] for ms, calls, site in prof]),
                  "",
                  "`selection.hpp` holds the selection (its dry runs of the legality tests, the samples placed one a "
                  "thread, the reservation steps), `adjacency.hpp` the fans and edges, `error_bound.hpp` the samples' "
                  "sort by face, `apply.hpp` the compaction.", ""]

    fig, ax = plt.subplots(figsize=(7, 3.6))
    xs = [r["round"] for r in round_rows]
    ax.bar(xs, [r["seconds"] * 1e3 for r in round_rows], color="#3b6ea5")
    ax.set_xlabel("round")
    ax.set_ylabel("ms on the GPU")
    ax2 = ax.twinx()
    ax2.plot(xs, [r["triangles"] / 1e6 for r in round_rows], color="#c0504d", marker=".")
    ax2.set_ylabel("triangles at the round's start (M)", color="#c0504d")
    ax.set_title(f"N = {n} paper surface on {meta.get('gpu', 'the GPU').split(',')[0]}: time and size per round")
    fig.tight_layout()
    fig.savefig(out / "rounds.png", dpi=110)

    lines += ["## Command, machine, commit", "",
              f"- Command: `{meta['script_cmd']}` on the device machine, after `scripts/gpu_check.sh prepare` here "
              "(Debian 12, g++ 12, nvcc 13.0, Release, `-DCMAKE_CUDA_ARCHITECTURES=90`); it ran", "", "  ```",
              f"  {shown(meta['bench_cmd'])}", f"  {shown(meta['reduce_cmd'])}", "  ```", "",
              "  with OUT the folder the files here were copied from.", "",
              f"- Build: {meta['source_state']}",
              f"- GPU: {meta.get('gpu', '?')}",
              f"- Host: {meta['cpu_model']}, {meta['cpus']} CPUs ({meta['cores_per_socket']} cores per socket), "
              f"{meta['memory']}, {meta['kernel']}",
              f"- Environment: `{meta.get('environment', '')}`",
              f"- Date: {meta['date']}; load average before {meta['load_before']}, after {meta['load_after']}",
              f"- Regenerate the page from the data here: `python3 scripts/report_reduce_gpu.py {out}`", ""]
    (out / "README.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv)
