#!/usr/bin/python3
"""Writes results/paper-reproduction.md, the paper's experiment as
tetiso measures it: speed-up against working MPI processes for 250, 125 and
63 domains (the paper's Fig. 11, plotted as speedup.png), the time of each
stage, raw and reduced triangle counts, the topology of each series' final
surface, what limits the speed-up (STREAM bandwidth, perf's cache misses,
the contention probe, idle workers), and the Fig. 10-style pictures that
scripts/render_surface.py draws.

    scripts/report_paper.py [INPUT ...] [--out results/paper-reproduction]

Each INPUT is an OUTDIR of scripts/paper_reproduction.sh or one of the files
in it: sweep outputs of scripts/sweep_speedup.py (any name, merged),
stream.json (bench_stream), check-dD.json (`tetiso check` of D domains'
surface), contention.json (scripts/probe_contention.py) and machine.txt (or
any *machine*.txt).
They are copied into OUT as sweep.json (merged), stream.json, check-dD.json,
contention.json and machine.txt, and the page, OUT.md beside the folder
(results/paper-reproduction.md), is written from OUT alone;
with no INPUT it is rewritten from what OUT holds. The pictures, render.json
and render-check.json (scripts/render_surface.py and `tetiso check` of the
drawn surface) stay in OUT across new inputs. Every number on the page comes
from those files. Dependencies: python3, python3-matplotlib for the
plots (without it the page is written without them).
"""
import argparse
import json
import os
import re
import shutil
import statistics
import sys
from collections import Counter
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_report_common import stamp, table, topology_summary  # noqa: E402
from sweep_speedup import merged, points, write  # noqa: E402

DOMAIN_STAGES = ("generate", "extract", "reduce")
SEAM_STAGES = ("merge", "region", "splice", "reduce")


def classify(path):
    """Which of the page's inputs a JSON file is, by its content."""
    data = json.loads(path.read_text())
    if "runs" in data:
        return "sweep"
    if "probes" in data:
        return "contention"
    if "kernel" in data and "results" in data:
        return "stream"
    if "topology" in data:
        return "check"
    sys.exit(f"report_paper: {path}: not a sweep, stream, check or contention output")


def check_domains(path):
    """D of a check output, from its name (check-dD.json) or the surface it names."""
    for text in (path.name, json.loads(path.read_text()).get("file", "")):
        match = re.search(r"-d(\d+)", text)
        if match:
            return int(match.group(1))
    sys.exit(f"report_paper: {path}: cannot tell which series it checks")


def gather(inputs, out):
    files = []
    for item in map(Path, inputs):
        files += sorted(item.iterdir()) if item.is_dir() else [item]
    sweeps = []
    for path in files:
        if path.suffix == ".txt" and "machine" in path.name:
            shutil.copyfile(path, out / "machine.txt")
        elif path.suffix != ".json" or path.resolve().parent == out.resolve() and path.name == "sweep.json":
            continue
        else:
            kind = classify(path)
            if kind == "sweep":
                sweeps.append(path)
            elif kind == "check":
                shutil.copyfile(path, out / f"check-d{check_domains(path)}.json")
            else:
                shutil.copyfile(path, out / f"{kind}.json")
    if sweeps:
        command = " ".join(["scripts/report_paper.py"] + [str(p) for p in inputs])
        meta, runs = merged(sweeps, command)
        write(str(out / "sweep"), meta, runs)
        for stale in ("sweep.csv",):
            (out / stale).unlink(missing_ok=True)  # the page's tables say what the CSV did


def load(out, name):
    path = out / name
    return json.loads(path.read_text()) if path.exists() else None


def machine_text(meta):
    m = meta["machine"]
    memory = f", {m['memory_gib']:.0f} GiB" if "memory_gib" in m else ""
    return f"{m['cpu']}, {m['cores']} cores{memory}, {m.get('L3 cache', '?')} L3, Linux {m['kernel']}"


def dates(meta):
    found = sorted({s["started"][:10] for s in meta.get("sources", []) + [meta] if s.get("started")})
    return ", ".join(found) or "not recorded"


def provenance(meta):
    """The two-line source of a figure drawn from the sweep."""
    return (f"tetiso run --lattice {meta['lattice']} under mpirun (scripts/sweep_speedup.py); commit "
            f"{meta['commit']}; {dates(meta)}\n{machine_text(meta)}")


def cpu_only(meta, runs):
    """Whether every run did its tasks on the CPU: asked with --device cpu, or
    made by a tetiso whose reports have no device (one without GPU tasks)."""
    asked = all("--device cpu" in s["command"] for s in meta.get("sources", [meta]))
    return asked or all("device" not in r["report"] for r in runs)


def median_report(reports):
    """The report whose job time is the median (the lower one of an even count)."""
    ordered = sorted(reports, key=lambda r: r["seconds"]["job"])
    return ordered[(len(ordered) - 1) // 2]


def stage_sums(report):
    sums = {("domain", s): 0.0 for s in DOMAIN_STAGES} | {("seam", s): 0.0 for s in SEAM_STAGES}
    busy = 0.0
    for task in report["tasks"]:
        busy += task["end"] - task["start"]
        for stage, seconds in task.get("stage_seconds", {}).items():
            sums[(task["kind"], stage)] = sums.get((task["kind"], stage), 0.0) + seconds
    return sums, busy


def fmt(value, digits=1):
    return f"{value:,.{digits}f}"


def plot_speedup(rows, meta, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    top = max(16, max(r["workers"] for r in rows) + 1)
    fig, ax = plt.subplots(figsize=(6.4, 5.4))
    ax.plot([0, top], [0, top], "k--", linewidth=1, label="ideal")
    for domains, marker in zip(sorted({r["domains"] for r in rows}, reverse=True), "osd^v"):
        points = sorted((r["workers"], r["speedup"]) for r in rows if r["domains"] == domains)
        ax.plot(*zip(*points), marker=marker, label=f"{domains} domains")
    ax.set_xlabel("working MPI processes")
    ax.set_ylabel("speed-up T(1) / T(P)")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    ax.set_title(f"Speed-up of the isosurface job, N = {meta['lattice']} (cf. the paper's Fig. 11)", fontsize=10)
    stamp(fig, provenance(meta))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_bandwidth(rows, stream, meta, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    base = stream["results"][0]
    for kind, style in (("triad", "k-"), ("copy", "k:")):
        key = f"{kind}_gb_s"
        ax.plot([r["threads"] for r in stream["results"]],
                [r[key] / r["threads"] / base[key] for r in stream["results"]], style,
                label=f"STREAM {kind}: bandwidth per thread / 1 thread's")
    for domains, marker in zip(sorted({r["domains"] for r in rows}, reverse=True), "osd^v"):
        points = sorted((r["workers"], r["efficiency"]) for r in rows if r["domains"] == domains)
        ax.plot(*zip(*points), marker=marker, label=f"job efficiency, {domains} domains")
    ax.set_xlabel("threads (STREAM) / working MPI processes (job)")
    ax.set_ylabel("fraction of the one-core rate")
    ax.set_ylim(0, 1.1)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=7)
    ax.set_title("Job efficiency against each core's share of memory bandwidth", fontsize=10)
    stamp(fig, provenance(meta) + "; STREAM: bench/bench_stream.cpp")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def speedup_rows(runs):
    return [{"domains": domains, "workers": p, "runs": len(reports), "seconds": seconds,
             "speedup": t1 / seconds if t1 else None, "efficiency": t1 / seconds / p if t1 else None,
             "report": median_report(reports), "reports": reports}
            for domains, p, reports, seconds, t1 in points(runs)]


def section_speedup(rows, out, have_plot):
    lines = ["## Speed-up", ""]
    if have_plot:
        lines += [f"![speed-up against working MPI processes]({out.name}/speedup.png)", ""]
    lines += ["Job seconds are the report's `seconds.job` (every task, domain generation included; MPI start-up "
              "and writing the surface excluded), the median where a point ran more than once. Speed-up is "
              "T(1)/T(P) within a series, efficiency speed-up / P. Peak memory is the largest resident set of any "
              "worker (`ru_maxrss`).", ""]
    body = []
    for r in rows:
        peaks = [max(x["peak_rss_kib"][1:]) / 1024 for x in r["reports"] if x.get("peak_rss_kib")]
        body.append([r["domains"], r["workers"], r["runs"], fmt(r["seconds"], 2),
                     fmt(r["speedup"], 2) if r["speedup"] else "no P = 1 run",
                     fmt(r["efficiency"], 2) if r["efficiency"] else "",
                     fmt(max(peaks), 0) if peaks else "not recorded"])
    lines += [table(["domains", "working processes P", "runs", "job s", "speed-up", "efficiency",
                     "worker peak MiB"], body), ""]
    missing = [d for d in (250, 125, 63) if not any(r["domains"] == d for r in rows)]
    if missing:
        lines += [f"Not measured in these data: {', '.join(f'{d} domains' for d in missing)}.", ""]
    return lines


def section_stages(rows):
    lines = ["## Where the time goes", "",
             "Seconds summed over every task of the run (domain tasks: generate the lattice domain, extract by "
             "marching tetrahedra, reduce; seam tasks: merge two pieces by global edge keys, find the region "
             "near the seam, splice, reduce it). Busy = the sum of all task times; idle = P × job seconds − busy, "
             "worker time spent waiting for work or messages.", ""]
    body = []
    for r in rows:
        sums, busy = stage_sums(r["report"])
        idle = r["workers"] * r["report"]["seconds"]["job"] - busy
        body.append([r["domains"], r["workers"]] + [fmt(sums[("domain", s)]) for s in DOMAIN_STAGES]
                    + [fmt(sum(sums[("seam", s)] for s in SEAM_STAGES))]
                    + [fmt(busy), f"{fmt(idle)} ({idle / (busy + idle):.0%})"])
    lines += [table(["domains", "P", "generate", "extract", "reduce (domains)", "seams (all stages)",
                     "busy", "idle"], body), ""]
    return lines


def section_triangles(rows, checks):
    lines = ["## Triangles and topology", "",
             "Raw = what marching tetrahedra produce over the whole lattice; reduced = the final surface after "
             "the domains' and the seams' reductions (criterion Φ, max error 0.25 lattice spacings). The surface "
             "of a series should not depend on P (tetiso's rounds are deterministic): distinct hashes counts the "
             "different SHA-256 of the surface files written by the runs of that series.", ""]
    body = []
    for domains in sorted({r["domains"] for r in rows}, reverse=True):
        reports = [x for r in rows if r["domains"] == domains for x in r["reports"]]
        raw, tri = reports[0]["raw_triangles"], reports[0]["triangles"]
        same = len({(x["raw_triangles"], x["triangles"]) for x in reports}) == 1
        hashes = {x["surface_sha256"] for x in reports if "surface_sha256" in x}
        body.append([domains, f"{raw:,}", f"{tri:,}" + ("" if same else " (differs between runs!)"),
                     f"{raw / tri:.1f}×", f"{len(hashes)} of {len(reports)} runs" if hashes else "not recorded"])
    lines += [table(["domains", "raw triangles", "reduced triangles", "ratio", "distinct hashes"], body), ""]
    if checks:
        lines += ["`tetiso check` of each series' final surface (self-intersections are counted where tetiso "
                  "was built with CGAL):", ""]
        body = []
        for domains, c in sorted(checks.items(), reverse=True):
            t = c["topology"]
            counts = Counter(f"genus {s['genus']}, {s['boundary_loops']} boundary loops"
                             + ("" if s["orientable"] else ", not orientable") for s in t["signatures"])
            sig = "; ".join(f"{n} × ({text})" if n > 1 else text for text, n in counts.items())
            body.append([domains, f"{t['triangles']:,}", t["components"], sig,
                         "yes" if t["manifold"] else "**no**", f"{t['non_manifold_edges']} / {t['non_manifold_vertices']}",
                         "yes" if t["oriented"] else "**no**", t["degenerate_triangles"],
                         f"{t['min_angle_deg']['below_1']:,}", f"{t['min_angle_deg']['min']:.3g}°",
                         "not counted" if c.get("self_intersections") is None else c["self_intersections"]])
        lines += [table(["domains", "triangles", "components", "signature", "manifold",
                         "non-manifold edges / vertices", "consistently oriented", "degenerate",
                         "angles < 1°", "smallest angle", "self-intersections"], body), ""]
        series = {r["domains"] for r in rows}
        unchecked = sorted(series - set(checks), reverse=True)
        if unchecked:
            lines += [f"Not checked in these data: {', '.join(map(str, unchecked))} domains.", ""]
    else:
        lines += ["No topology check of the speed-up runs' surfaces in these data (scripts/paper_reproduction.sh "
                  "writes one per series); the drawn surface's is under Pictures.", ""]
    return lines


def section_limits(rows, stream, contention, have_plot, summary, out):
    lines = ["## What limits the speed-up", "",
             "The paper puts its lost speed-up down to memory bandwidth: the more processes run, the more "
             "they load the memory subsystem. Efficiency E = T(1)/(P·T(P)) splits into two factors: how much "
             "slower each task runs when P workers run at once (inflation = busy seconds at P / busy seconds "
             "at 1), and how much of the P workers' time goes to tasks (utilisation = busy / (P × job seconds)). "
             "Bandwidth can only act through the first.", ""]
    ones = {r["domains"]: r for r in rows if r["workers"] == 1}
    body = []
    worst = None
    for r in rows:
        if r["workers"] == 1 or r["domains"] not in ones:
            continue
        busy1 = stage_sums(ones[r["domains"]]["report"])[1]
        busy = stage_sums(r["report"])[1]
        inflation = busy / busy1
        utilisation = busy / (r["workers"] * r["report"]["seconds"]["job"])
        body.append([r["domains"], r["workers"], fmt(r["efficiency"], 2), f"{inflation:.2f}×", f"{utilisation:.0%}"])
        if worst is None or r["workers"] > worst[1]:
            worst = (r["domains"], r["workers"], inflation, utilisation, r)
    if body:
        lines += [table(["domains", "P", "efficiency", "task inflation", "utilisation"], body), ""]
    if stream:
        res = {x["threads"]: x for x in stream["results"]}
        one = res[min(res)]
        lines += [f"Memory bandwidth of the machine, {stream['kernel']} over {stream['array_mib']} MiB arrays "
                  "(bench/bench_stream.cpp, threads pinned one per core):", ""]
        lines += [table(["threads", "copy GB/s", "triad GB/s", "triad per thread / 1 thread's"],
                        [[t, fmt(x["copy_gb_s"]), fmt(x["triad_gb_s"]), f"{x['triad_gb_s'] / t / one['triad_gb_s']:.2f}"]
                         for t, x in sorted(res.items())]), ""]
        if have_plot:
            lines += [f"![job efficiency against the per-core share of STREAM bandwidth]({out.name}/bandwidth.png)", ""]
    else:
        lines += ["No STREAM measurement in these data (scripts/paper_reproduction.sh runs bench/bench_stream.cpp).",
                  ""]
    if worst:
        domains, p, inflation, utilisation, r = worst
        report = r["report"]
        peaks = report.get("peak_rss_kib")
        traffic = None
        if report.get("perf") and {"LLC-load-misses", "LLC-store-misses"} <= set(report["perf"]):
            misses = report["perf"]["LLC-load-misses"] + report["perf"]["LLC-store-misses"]
            traffic = ("perf", misses * 64 / report["wall_seconds"] / 1e9)
        elif peaks:
            # A domain task builds its domain, piece and reduction state
            # afresh: about a worker's resident set, touched at least once.
            touched = domains * statistics.median(peaks[1:]) * 1024
            traffic = ("estimate", touched / report["seconds"]["job"] / 1e9, statistics.median(peaks[1:]) / 1024)
        text = [f"At P = {p} ({domains} domains) the tasks take {inflation:.2f}× their time with one worker, and "
                f"the workers "
                f"are busy {utilisation:.0%} of the job: efficiency {r['efficiency']:.2f} ≈ "
                f"{utilisation:.2f} / {inflation:.2f}."]
        if stream:
            res = {x["threads"]: x for x in stream["results"]}
            near = min(res, key=lambda t: abs(t - p))
            share = res[near]["triad_gb_s"] / near / res[min(res)]["triad_gb_s"]
            text.append(f"A task bound by bandwidth as STREAM's triad is would run {1 / share:.2f}× as long with "
                        f"{near} cores streaming at once (each gets {share:.2f} of the bandwidth one core gets "
                        "alone).")
            if traffic:
                kind, gbs = traffic[:2]
                source = ("perf's last-level-cache load and store misses × 64 B over the run's wall time"
                          if kind == "perf" else
                          f"an estimate without cache-miss counts: {domains} domain tasks each touching a "
                          f"worker's median peak resident set, {traffic[2]:.0f} MiB, once, over the job's seconds")
                text.append(f"The job moves about {gbs:.1f} GB/s ({source}) against {res[near]['triad_gb_s']:.0f} "
                            f"GB/s that STREAM's triad sustains with {near} threads ({gbs / res[near]['triad_gb_s']:.0%}).")
            bound = inflation >= 0.75 / share and (traffic is None or traffic[1] >= 0.5 * res[near]["triad_gb_s"])
            summary.append(f"Memory bandwidth: {'the limit' if bound else 'not the limit'} at P = {p} (tasks "
                           f"{inflation:.2f}× their one-worker time against {1 / share:.2f}× for a bandwidth-bound "
                           "kernel; see below).")
            if bound:
                text.append("**Bandwidth is the limit here**, as the paper found: the tasks slow down about as "
                            "much as a bandwidth-bound kernel would, and the job's traffic approaches what the "
                            "memory delivers.")
            else:
                lost_idle = 1 - utilisation
                text.append(f"**Bandwidth is not the limit here.** The tasks slow down far less than a "
                            f"bandwidth-bound kernel would ({inflation:.2f}× against {1 / share:.2f}×)"
                            + (", and the job uses a small part of the bandwidth" if traffic and
                               traffic[1] < 0.5 * res[near]["triad_gb_s"] else "")
                            + f". What remains is the {lost_idle:.0%} of worker time spent idle (waiting for work or "
                            f"messages) and the tasks' own {inflation:.2f}× time when every core is busy.")
        lines += [" ".join(text), ""]
    if contention:
        probes = contention["probes"]
        body = [[name, fmt(statistics.median(p["alone_s"]), 2), fmt(statistics.median(p["together_s"]), 2),
                 f"{p['ratio_of_medians']:.2f}×"] for name, p in probes.items()]
        lines += [f"Contention probe (scripts/probe_contention.py): one single-thread command alone on one core, "
                  f"then as {len(contention['cores'])} pinned copies at once. compute is a loop with no memory "
                  "traffic (a ratio above 1 means the cores clock down); small reduces a surface that fits a "
                  "core's L2 cache; domain reduces a domain-sized surface (its working set fits the shared L3 "
                  "alone, not as many copies).", ""]
        lines += [table(["probe", "alone s (median)", "together s (median)", "ratio"], body), ""]
    return lines


def section_pictures(out, rows):
    render = load(out, "render.json")
    if not render:
        return ["## Pictures", "", "Not rendered yet: scripts/render_surface.py draws them.", ""]
    lines = ["## Pictures", "",
             f"A fragment of the final surface ({render['domains']} domains), reduced (left) and unreduced "
             "(right, the same job with `--no-reduce`), clipped to the same box "
             f"{render['box']} and drawn with their edges, like the paper's Fig. 10: "
             f"{render['fragment_triangles']['reduced']:,} against {render['fragment_triangles']['raw']:,} "
             "triangles in the box.", "", f"![reduced and raw fragment]({out.name}/fragment.png)", "",
             f"The whole reduced surface ({render['triangles']['reduced']:,} triangles; raw "
             f"{render['triangles']['raw']:,}):", "", f"![the reduced surface]({out.name}/surface.png)", "",
             f"Made with `{render['command']}` from `{render['jobs']['reduced']}` and `{render['jobs']['raw']}`; "
             f"{render['machine']}; commit {render['commit']}; {render['date']}; VTK {render['vtk']} offscreen. "
             "The surfaces are byte-identical on any machine, so they are drawn where the speed-up was not "
             "measured.", ""]
    check = load(out, "render-check.json")
    if check:
        crossings = check.get("self_intersections")
        lines += [f"`tetiso check` of the drawn reduced surface: {topology_summary(check)}; self-intersections "
                  + ("not counted" if crossings is None else f"{crossings}") + f" ({out.name}/render-check.json).", ""]
    same = [r for r in rows if r["domains"] == render["domains"]]
    if same:
        counts = {x["triangles"] for r in same for x in r["reports"]}
        agree = counts == {render["triangles"]["reduced"]}
        lines += [f"The speed-up runs with {render['domains']} domains gave "
                  f"{', '.join(f'{c:,}' for c in sorted(counts))} triangles: "
                  + ("the same surface size." if agree else "**not the drawn surface's size** (different commits)."),
                  ""]
    return lines


def section_provenance(meta, out):
    lines = ["## Command, machine, commit, date", "",
             f"- Page: `scripts/report_paper.py` from the files in {out.name}/ (sweep.json merges "
             f"{len(meta.get('sources', [])) or 1} sweep output(s); each run keeps its report with every task)."]
    for source in meta.get("sources", [meta]):
        lines.append(f"- `{source['command']}` (commit {source['commit']}, started "
                     f"{source.get('started', 'not recorded')})")
    lines += [f"- Machine: {machine_text(meta)}; MPI ranks bound to cores (`--bind-to core`); one controlling "
              "rank beside the P working ones", f"- Commit: {meta['commit']}", f"- Date: {dates(meta)}", ""]
    if (out / "machine.txt").exists():
        lines += [f"{out.name}/machine.txt holds the machine's lscpu, memory, kernel and MPI version.", ""]
    # The same points as the calls above, one call each, with the checks.
    calls = [re.search(r"--points (\S+)", source["command"]) for source in meta.get("sources", [meta])]
    calls = [m.group(1) for m in calls if m]
    lines += ["To measure the same points again (a device machine with 16 cores, one call each) and rewrite "
              "this page:", "", "```"]
    lines += [f"TETISO_BIN=build/core/tetiso EXTRAS=check scripts/paper_reproduction.sh out/call{i} 550 {points}"
              for i, points in enumerate(calls, 1)]
    lines += ["scripts/report_paper.py " + " ".join(f"out/call{i}" for i in range(1, len(calls) + 1)), "```", ""]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("inputs", nargs="*")
    parser.add_argument("--out", default="results/paper-reproduction")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.inputs:
        for stale in out.glob("check-d*.json"):
            stale.unlink()  # new inputs replace the old measurement whole
        for name in ("stream.json", "contention.json", "machine.txt"):
            (out / name).unlink(missing_ok=True)
        gather(args.inputs, out)
    data = load(out, "sweep.json")
    if not data:
        sys.exit(f"report_paper: no sweep.json in {out} (give the outputs of scripts/paper_reproduction.sh)")
    meta = {k: v for k, v in data.items() if k != "runs"}
    stream, contention = load(out, "stream.json"), load(out, "contention.json")
    checks = {int(p.stem[len("check-d"):]): json.loads(p.read_text()) for p in out.glob("check-d*.json")}
    rows = speedup_rows(data["runs"])
    plotted = [r for r in rows if r["speedup"] is not None]
    have_plot = False
    try:
        import matplotlib  # noqa: F401
        have_plot = bool(plotted)
    except ImportError:
        print("report_paper: matplotlib missing: no plots", file=sys.stderr)
    (out / "sweep.png").unlink(missing_ok=True)  # sweep_speedup's own plot; speedup.png replaces it
    if have_plot:
        plot_speedup(plotted, meta, out / "speedup.png")
        if stream:
            plot_bandwidth(plotted, stream, meta, out / "bandwidth.png")
    lines = [f"# The paper's experiment: N = {meta['lattice']}, 250, 125 and 63 domains", "",
             "The test problem of the paper's section \"Testing software implementation\": a 5 × 5 × 5 cube, a "
             f"lattice of {meta['lattice']}³ nodes (6 tetrahedra per cell), field f = 2cos(10x) + 2sin(10y) + "
             "cos(10z), isosurface f = 0.5 — `tetiso run --lattice 500` with its defaults — split by recursive "
             "bisection into 250, 125 or 63 domains (5·10⁵, 10⁶ and 2·10⁶ nodes each, as in the paper) and run "
             "by P working MPI processes beside one controlling rank"
             + (", on the CPU only (`--device cpu`, or a tetiso without GPU tasks), as the paper's Fig. 11 was."
                if cpu_only(meta, data["runs"]) else
                ". **Some runs may have sent tasks to a GPU** (no `--device cpu`): the paper's Fig. 11 used none."),
             ""]
    summary = []
    for domains in sorted({r["domains"] for r in plotted}, reverse=True):
        top = max((r for r in plotted if r["domains"] == domains), key=lambda r: r["workers"])
        if top["workers"] > 1:
            summary.append(f"{domains} domains: speed-up **{top['speedup']:.2f}** with {top['workers']} working "
                           f"processes (efficiency {top['efficiency']:.2f}; {top['seconds']:.1f} s against "
                           f"{top['seconds'] * top['speedup']:.1f} s).")
    first = rows[0]["report"]
    summary.append(f"Reduction: {first['raw_triangles']:,} raw triangles → "
                   + ", ".join(f"{r['report']['triangles']:,} ({r['domains']} domains)"
                               for r in rows if r is next(x for x in rows if x["domains"] == r["domains"])) + ".")
    limits = section_limits(plotted, stream, contention, have_plot and bool(stream), summary, out)
    sound = [c for c in checks.values()] + ([load(out, "render-check.json")] if load(out, "render-check.json") else [])
    if sound:
        ok = all(c["topology"]["manifold"] and c["topology"]["oriented"] and not c["topology"]["degenerate_triangles"]
                 for c in sound)
        summary.append(f"Topology: {len(sound)} surface(s) checked, "
                       + ("all manifold, consistently oriented, without degenerate triangles." if ok else
                          "**some unsound: see the table.**"))
    lines += ["## Summary", ""] + [f"- {item}" for item in summary] + [""]
    lines += section_speedup(rows, out, have_plot)
    lines += section_stages(rows)
    lines += section_triangles(rows, checks)
    lines += limits
    lines += section_pictures(out, rows)
    lines += section_provenance(meta, out)
    page = out.with_name(out.name + ".md")  # results/paper-reproduction.md; the folder holds its data
    page.write_text("\n".join(lines))
    print(f"wrote {page}")


if __name__ == "__main__":
    main()
