"""The spec of each results page for tools/render_results.py: which data of
its folder it reads, the tables and plots it makes, the derived figures its
page.md names. Each spec takes the folder and returns the names the page's
placeholders use; the prose is in the page.md."""
import json
import re
import statistics
from collections import Counter

from render_results import (bench_provenance, bullets, figure, load, load_aggregates, plot_timeline, runs_provenance,
                            save, table, topology_summary)
from results_pages_gpu import gpu_streams, hardware_comparison, reduce_batch, reduce_gpu


def mega(value):
    return f"{value / 1e6:.2f}"


def extract(folder):
    pattern = r"^extract/(tetiso|vtk)/N:(\d+)/threads:(\d+)(/real_time)?$"
    context, cases = load_aggregates(folder / "bench_extract.json", pattern,
                                     lambda m: (m[1], int(m[2]), int(m[3])))
    meta = load(folder, "meta.json")
    rate = {k: c["median"]["tets/s"] for k, c in cases.items()}
    sizes = sorted({n for _, n, _ in cases})
    most = max(t for _, _, t in cases)
    ratios = {n: rate["tetiso", n, 1] / rate["vtk", n, 1] for n in sizes}
    rows = []
    for n in sizes:
        tp, vp = rate.get(("tetiso", n, most)), rate.get(("vtk", n, most))
        rows.append([n, f"{int(cases['tetiso', n, 1]['median']['tets']):,}", mega(rate["tetiso", n, 1]),
                     mega(rate["vtk", n, 1]), f"**{ratios[n]:.2f}×**", mega(tp) if tp else "—",
                     mega(vp) if vp else "—", f"{tp / vp:.2f}×" if tp and vp else "—"])
    order = sorted(cases, key=lambda k: (k[1], k[0], k[2]))
    counts = {k: (int(cases[k]["median"]["vertices"]), int(cases[k]["median"]["triangles"])) for k in cases}
    memory = [json.loads(line) for line in (folder / "memory.jsonl").read_text().splitlines() if line.strip()]

    fig, ax = figure(max(6, len(order) * 0.9), 4)
    ax.bar(range(len(order)), [rate[k] / 1e6 for k in order],
           color=["tab:blue" if k[0] == "tetiso" else "tab:gray" for k in order])
    ax.set_xticks(range(len(order)), [f"{i}\nN={n}, {t}t" for i, n, t in order], fontsize=7)
    ax.set_ylabel("Mtets/s (median)")
    ax.set_title("Marching tetrahedra throughput")
    save(fig, folder / "throughput.png", f"{meta['script_cmd']}; commit {meta['commit'][:12]}; {meta['date']}\n"
         f"{meta['cpu_model']}, {meta['cpus']} CPUs, {meta['kernel']}", dpi=120)
    return dict(
        context=context, ratios=ratios,
        fastest_ratios={n: cases["vtk", n, 1]["min_ms"] / cases["tetiso", n, 1]["min_ms"] for n in sizes},
        throughput=table(["N", "tetrahedra", "tetiso 1 thread", "VTK sequential", "ratio", f"tetiso {most} threads",
                          f"VTK {most} threads", "ratio"], rows),
        cases_table=table(["case", "label", "median time (ms)", "min time (ms)", "cv", "Mtets/s (median)", "vertices",
                           "triangles", "repetitions"],
                          [[f"extract/{i}/N:{n}/threads:{t}", cases[i, n, t]["median"].get("label", ""),
                            f"{cases[i, n, t]['time_ms']:.1f}", f"{cases[i, n, t]['min_ms']:.1f}",
                            f"{100 * cases[i, n, t]['cv']:.1f} %", mega(rate[i, n, t]), f"{counts[i, n, t][0]:,}",
                            f"{counts[i, n, t][1]:,}", int(cases[i, n, t]["median"]["repetitions"])]
                           for i, n, t in order]),
        mismatches=[f"extract/{i}/N:{n}/threads:{t}" for i, n, t in order if counts[i, n, t] != counts["tetiso", n, 1]],
        memory_table=table(["method", "N", "nodes", "threads", "after domain (MB)", "peak (MB)", "peak (MiB)"],
                           [[m["method"], m["n"], f"{m['nodes']:,}", m["threads"],
                             f"{m['vm_hwm_after_domain_bytes'] / 1e6:.1f}", f"**{m['vm_hwm_bytes'] / 1e6:.1f}**",
                             f"{m['vm_hwm_bytes'] / 2**20:.1f}"] for m in memory]),
        peaks={m["threads"]: m["vm_hwm_bytes"] / 1e6 for m in memory if m["method"] == "tetiso"},
        provenance=bench_provenance(meta, context))


REDUCERS = {"tetiso": "tetiso reduce", "meshopt": "meshopt_simplify", "cgal": "CGAL edge_collapse (Garland–Heckbert)",
            "openmesh": "OpenMesh Decimater (quadric)"}


def reduce(folder, n=100):
    """results/reduce at N = n, the lattice the page's targets are stated for."""
    pattern = r"^reduce/(tetiso|meshopt|cgal|openmesh)/N:(\d+)/threads:(\d+)(/repeats:\d+)?(/real_time)?$"
    context, aggregates = load_aggregates(folder / "bench_reduce.json", pattern,
                                          lambda m: (m[1], int(m[2]), int(m[3])))
    cases = {}
    for key in sorted((k for k in aggregates if k[1] == n), key=lambda k: (list(REDUCERS).index(k[0]), k[2])):
        a = aggregates[key]
        c = cases[key[0], key[2]] = {k: v for k, v in a["median"].items() if isinstance(v, (int, float))}
        c.update(seconds=a["time_ms"] / 1e3, min_seconds=a["min_ms"] / 1e3, cv=a["cv"],
                 rate=c["triangles_in"] / (a["time_ms"] / 1e3))  # the rate of the median time, as the table shows

    def kept(c):
        return (c["same_topology"] == 1 and not c["non_manifold_edges"] and not c["non_manifold_vertices"]
                and not c["misoriented_edges"])

    def crossings(c):
        if "self_intersections" in c:
            return f"{int(c['self_intersections']):,}"
        if c["non_manifold_edges"] or c["non_manifold_vertices"]:
            return "not measured (non-manifold: CGAL cannot take it)"
        return "not measured"

    rows = [[REDUCERS[m], t, int(c["repetitions"]), f"{int(c['triangles_in']):,}", f"{int(c['triangles_out']):,}",
             f"{c['triangles_in'] / c['triangles_out']:.2f}×", f"**{c['seconds']:.3f}**", f"{c['min_seconds']:.3f}",
             f"{100 * c['cv']:.1f} %", f"**{c['rate'] / 1e6:.2f}**", f"{c['hausdorff']:.5f}", f"{c['hausdorff_h']:.3f}",
             "yes" if c["same_topology"] == 1 else "**no**",
             f"{int(c['non_manifold_edges'])} / {int(c['non_manifold_vertices'])}", f"{int(c['misoriented_edges'])}",
             f"{int(c['degenerate_triangles'])} / {int(c['near_degenerate_triangles'])}", crossings(c)]
            for (m, t), c in cases.items()]
    tetiso = {t: c for (m, t), c in cases.items() if m == "tetiso"}
    outputs = {int(c["triangles_out"]) for c in tetiso.values()}
    target = max(outputs)
    sanity = [f"Sanity check: every tetiso case produced the same {target:,} triangles (the output does not depend "
              "on the thread count)." if len(outputs) == 1 else "**Sanity check failed:** tetiso's triangle counts "
              "differ between thread counts: " + ", ".join(f"{x:,}" for x in sorted(outputs)) + "."]
    for (m, t), c in cases.items():
        if m != "tetiso" and t == 1:
            out = int(c["triangles_out"])
            sanity.append(f"{REDUCERS[m]} was asked for at most {target:,} triangles and produced "
                          + ("exactly that count." if out == target else f"{out:,}, {target - out:,} fewer."))
    return dict(
        context=context, n=n, raw={k.split("/")[-1]: v for k, v in context.items() if k.startswith(f"raw/N:{n}/")},
        figures=table(["method", "threads", "runs", "triangles in", "triangles out", "ratio", "median s", "fastest s",
                       "cv", "Mtris/s input", "Hausdorff", "Hausdorff / h", "same topology",
                       "non-manifold edges / vertices", "misoriented edges", "degenerate / near-degenerate",
                       "self-intersections"], rows),
        t1=cases["tetiso", 1], mo=cases["meshopt", 1], tetiso=tetiso, kept=kept, crossings=crossings, title=REDUCERS,
        careful={m: cases[m, 1] for m in ("cgal", "openmesh") if (m, 1) in cases}, sanity="\n".join(sanity),
        provenance=bench_provenance(load(folder, "meta.json"), context))


def fuzz(folder):
    readers = [json.loads(p.read_text()) for p in sorted(folder.glob("*.json"))]
    campaigns = {}
    for r in readers:
        key = tuple(r[k] for k in ("command", "commit", "started", "machine", "compiler", "build"))
        campaigns.setdefault(key, []).append(r["reader"])
    label = {reader: chr(ord("A") + i) for i, names in enumerate(campaigns.values()) for reader in names}
    return dict(
        clean=all(r["finding"] is None for r in readers),
        readers_table=table(["reader", "inputs run", "exec/s", "coverage (edges)", "features", "corpus entries",
                             "findings", "campaign"],
                            [[r["reader"], f"{r['inputs']:,}", f"{r['exec_per_s']:,}", f"{r['coverage_edges']:,}",
                              f"{r['features']:,}" if r.get("features") else "not recorded",
                              f"{r['corpus_entries']:,}", r["finding"] or "none", label[r["reader"]]]
                             for r in readers]),
        campaigns=bullets(f"Campaign {label[names[0]]} ({', '.join(names)}): `{command}`; commit {commit}; started "
                          f"{started}; {machine}; {compiler}, {build}"
                          for (command, commit, started, machine, compiler, build), names in campaigns.items()))


def solver_read(folder):
    data = load(folder, "runs.json")
    return dict(data=data, raw=next(statistics.median(p["seconds"]) for p in data["pieces"] if p["variant"] == "raw"),
                pieces=table(["piece", "bytes", "median s", "each run, s"],
                             [[p["label"], f"{p['bytes']:,}", f"{statistics.median(p['seconds']):.3f}",
                               ", ".join(f"{t:.3f}" for t in p["seconds"])] for p in data["pieces"]]))


def mesh(folder):
    log = (folder / "split_job.log").read_text()
    split_seconds, same = re.search(r"tetiso split: ([\d.]+) s; same surface: (\w+)", log).groups()
    rows, reports = [], {}
    for mode, job in (("mesh", "`run --mesh cube.1 --domains {}`"), ("split", "`run --split DIR`")):
        r = reports[mode] = load(folder, f"{mode}.json")
        wall = float(re.search(rf"run --{mode}: .*wall ([\d.]+) s", log).group(1))
        peaks = {x["rank"]: x["peak_rss_kib"] / 1024 for x in map(json.loads, (folder / f"rss-{mode}.jsonl")
                                                                   .read_text().splitlines())}
        workers = [v for k, v in peaks.items() if k != 0]
        rows.append([job.format(r["domains"]), f"{wall:.2f}", f"{r['seconds']['job']:.2f}",
                     f"{min(workers):,.1f}–{max(workers):,.1f}", f"{peaks[0]:,.1f}",
                     f"{sum(peaks.values()) / 1024:.2f}", f"{r['triangles']:,}"])
    return dict(m=reports["mesh"], same=same, split_seconds=float(split_seconds),
                jobs=table(["job", "wall s", "job s", "peak per worker MiB", "peak rank 0 MiB", "peaks summed GiB",
                            "triangles"], rows),
                provenance=runs_provenance(load(folder, "meta.json")))


def extract_gpu(folder):
    context, cases = load_aggregates(folder / "device/bench_extract.json",
                                     r"(extract|domain)/([\w-]+)/N:(\d+)/threads:(\d+)/real_time",
                                     lambda m: (m[1], m[2], int(m[3]), int(m[4])))
    sizes = sorted({k[2] for k in cases})
    threads = max(k[3] for k in cases)

    def cell(case, stages=False):
        text = f"{case['time_ms']:,.1f} ({case['min_ms']:,.1f})"
        parts = ("upload_s", "compute_s", "download_s")
        return text + (" = " + " / ".join(f"{case['median'][k] * 1e3:.2f}" for k in parts) if stages else "")

    def summary(log):  # a test log's last summary line
        for pattern in (r"\d+% tests passed.*out of \d+", r"\d+ passed, \d+ failed", r"\[  PASSED  \] \d+ tests?"):
            found = re.findall(pattern, log.read_text())
            if found:
                return found[-1].replace("[  PASSED  ]", "passed:")
        return "no summary line"

    return dict(
        context=context, n=sizes[0], threads=threads, ms=lambda who, t: cases["extract", who, sizes[0], t]["time_ms"],
        extraction=table(["N", "tetrahedra", "triangles", "CPU, 1 thread", f"CPU, {threads} threads",
                          "GPU, domain uploaded", "GPU, lattice"],
                         [[n, f"{cases['extract', 'tetiso', n, 1]['median']['tets']:,.0f}",
                           f"{cases['extract', 'tetiso', n, 1]['median']['triangles']:,.0f}",
                           cell(cases["extract", "tetiso", n, 1]), cell(cases["extract", "tetiso", n, threads]),
                           cell(cases["extract", "gpu", n, 1], True),
                           "**" + cell(cases["extract", "gpu-lattice", n, 1], True) + "**"] for n in sizes]),
        domain=table(["N", "CPU, 1 thread", "GPU, lattice"],
                     [[n, cell(cases["domain", "tetiso", n, 1]), cell(cases["domain", "gpu", n, 1])] for n in sizes]),
        tests=bullets(f"`device/{log.name}`: {summary(log)}" for log in sorted((folder / "device").glob("*.log"))),
        provenance=runs_provenance(load(folder, "meta.json")))


def busy(report):
    tasks = sum(t["end"] - t["start"] for t in report["tasks"])
    return tasks, tasks / (report["workers"] * report["seconds"]["job"])


def scale(folder):
    rows = []
    for name, label in (("n1000-d1000", "N = 1000, 1000 domains"), ("n500-d125", "N = 500, 125 domains")):
        r, c = load(folder, f"{name}.json"), load(folder, f"{name}-check.json")
        tasks, share = busy(r)
        angles = c["topology"]["min_angle_deg"]
        rows.append([label, f"**{r['seconds']['job']:.2f}**", f"{tasks:.1f}", f"{share:.0%}",
                     f"{r['raw_triangles']:,} → {r['triangles']:,} ({r['raw_triangles'] / r['triangles']:.0f}×)",
                     f"{r['raw_triangles'] / r['seconds']['job'] / 1e6:.2f} M",
                     f"{angles['below_1']:,} ({angles['below_1'] / angles['triangles']:.3%})", topology_summary(c)])
    fields = []
    for field, expected in (("sphere", "genus 0, closed"), ("torus", "genus 1, closed"),
                            ("gyroid", "no closed form at this lattice (the gyroid is cut by the cube)")):
        r, c = load(folder, f"fields-{field}.json"), load(folder, f"fields-{field}-check.json")
        fields.append([field, f"{r['seconds']['job']:.2f}", f"{r['raw_triangles']:,} → {r['triangles']:,} "
                       f"({r['raw_triangles'] / r['triangles']:.0f}×)", f"{busy(r)[1]:.0%}", topology_summary(c),
                       expected])
    mem = load(folder, "memory-n1000-d1000.json")
    plot_timeline(folder / "n1000-d1000.json", folder / "timeline.png")
    return dict(
        result=table(["run", "job s", "tasks' sum s", "workers busy", "raw → reduced triangles",
                      "raw triangles per s", "angles below 1°", "`tetiso check`"], rows),
        big=load(folder, "n1000-d1000.json"), small=load(folder, "n500-d125.json"), mem=mem,
        peaks=[k / 1024 for k in mem["peak_rss_kib"]], domain_mib=mem["tets"] / mem["domains"] * 16 / 2**20,
        fields=table(["field", "job s", "raw → reduced triangles", "workers busy", "`tetiso check`", "expected"],
                     fields),
        provenance=runs_provenance(load(folder, "meta.json")))


# The least a round must move through device memory, per triangle at the
# round's start: positions and triangles read; fans (face, next, prev per
# corner), edges (two ends and a slot), face records (32 B), cones (16 B a
# vertex), the operations' kind, priority, position, bound and survivor (per
# edge), the order and reservations of the selection, and the compacted
# surface written once each. About 1.5 edges and 0.5 vertices a triangle.
def stage_sums(report):
    """Summed seconds per (task kind, stage), and the sum of all task times."""
    sums = Counter()
    for task in report["tasks"]:
        sums.update({(task["kind"], stage): seconds for stage, seconds in task.get("stage_seconds", {}).items()})
    return sums, sum(task["end"] - task["start"] for task in report["tasks"])


def paper_reproduction(folder):
    """results/paper-reproduction.md from the folder that tools/collect_results.py paper fills."""
    from sweep_speedup import points
    data = load(folder, "sweep.json")
    meta = {k: v for k, v in data.items() if k != "runs"}
    sources = meta.get("sources", [meta])
    stream, render = load(folder, "stream.json"), load(folder, "render.json")
    render_check = load(folder, "render-check.json")
    checks = {int(p.stem[len("check-d"):]): json.loads(p.read_text()) for p in folder.glob("check-d*.json")}
    rows = []
    for domains, p, reports, seconds, t1 in points(data["runs"]):
        report = sorted(reports, key=lambda r: r["seconds"]["job"])[(len(reports) - 1) // 2]  # the median (lower) run
        rows.append(dict(domains=domains, workers=p, reports=reports, report=report, seconds=seconds,
                         speedup=t1 / seconds, efficiency=t1 / seconds / p))
    series = sorted({r["domains"] for r in rows}, reverse=True)
    m = meta["machine"]
    machine = (f"{m['cpu']}, {m['cores']} cores, {m['memory_gib']:.0f} GiB, {m.get('L3 cache', '?')} L3, "
               f"Linux {m['kernel']}")
    dates = ", ".join(sorted({s["started"][:10] for s in sources + [meta] if s.get("started")}))
    driver = sources[0]["command"].split()[0]  # the sweep program, as the data record it
    stamp = (f"tetiso run --lattice {meta['lattice']} under mpirun ({driver}); commit {meta['commit']}; "
             f"{dates}\n{machine}")

    summary, speedup, stages, factors = [], [], [], []
    ones = {r["domains"]: stage_sums(r["report"])[1] for r in rows if r["workers"] == 1}
    for r in rows:
        peaks = [max(x["peak_rss_kib"][1:]) / 1024 for x in r["reports"] if x.get("peak_rss_kib")]
        speedup.append([r["domains"], r["workers"], len(r["reports"]), f"{r['seconds']:,.2f}", f"{r['speedup']:,.2f}",
                        f"{r['efficiency']:,.2f}", f"{max(peaks):,.0f}" if peaks else "not recorded"])
        sums, busy = stage_sums(r["report"])
        idle = r["workers"] * r["report"]["seconds"]["job"] - busy
        seams = sum(v for (kind, _), v in sums.items() if kind == "seam")
        stages.append([r["domains"], r["workers"]]
                      + [f"{sums['domain', s]:,.1f}" for s in ("generate", "extract", "reduce")]
                      + [f"{seams:,.1f}", f"{busy:,.1f}", f"{idle:,.1f} ({idle / (busy + idle):.0%})"])
        r["inflation"] = busy / ones[r["domains"]]
        r["utilisation"] = busy / (r["workers"] * r["report"]["seconds"]["job"])
        if r["workers"] > 1:
            factors.append([r["domains"], r["workers"], f"{r['efficiency']:,.2f}", f"{r['inflation']:.2f}×",
                            f"{r['utilisation']:.0%}"])
    for domains in series:
        top = max((r for r in rows if r["domains"] == domains), key=lambda r: r["workers"])
        summary.append(f"{domains} domains: speed-up **{top['speedup']:.2f}** with {top['workers']} working processes "
                       f"(efficiency {top['efficiency']:.2f}; {top['seconds']:.1f} s against "
                       f"{top['seconds'] * top['speedup']:.1f} s).")
    first = {d: next(r["report"] for r in rows if r["domains"] == d) for d in series}
    summary.append(f"Reduction: {rows[0]['report']['raw_triangles']:,} raw triangles → "
                   + ", ".join(f"{first[d]['triangles']:,} ({d} domains)" for d in series) + ".")

    # What limits the speed-up, at the largest P: the tasks' slow-down against
    # a bandwidth-bound kernel's (STREAM's triad per thread) and the traffic.
    worst = max((r for r in rows if r["workers"] > 1), key=lambda r: r["workers"])  # the first series' on a tie
    p, report = worst["workers"], worst["report"]
    res = {x["threads"]: x for x in stream["results"]}
    near = min(res, key=lambda t: abs(t - p))
    share = res[near]["triad_gb_s"] / near / res[min(res)]["triad_gb_s"]
    if {"LLC-load-misses", "LLC-store-misses"} <= set(report.get("perf", {})):
        misses = report["perf"]["LLC-load-misses"] + report["perf"]["LLC-store-misses"]
        gbs = misses * 64 / report["wall_seconds"] / 1e9
        source = "perf's last-level-cache load and store misses × 64 B over the run's wall time"
    else:  # a domain task builds its domain, piece and reduction state afresh: about a worker's resident set
        peak = statistics.median(report["peak_rss_kib"][1:])
        gbs = worst["domains"] * peak * 1024 / report["seconds"]["job"] / 1e9
        source = (f"an estimate without cache-miss counts: {worst['domains']} domain tasks each touching a worker's "
                  f"median peak resident set, {peak / 1024:.0f} MiB, once, over the job's seconds")
    inflation, utilisation = worst["inflation"], worst["utilisation"]
    bound = inflation >= 0.75 / share and gbs >= 0.5 * res[near]["triad_gb_s"]
    summary.append(f"Memory bandwidth: {'the limit' if bound else 'not the limit'} at P = {p} (tasks {inflation:.2f}× "
                   f"their one-worker time against {1 / share:.2f}× for a bandwidth-bound kernel; see below).")
    limit = (f"At P = {p} ({worst['domains']} domains) the tasks take {inflation:.2f}× their time with one worker, "
             f"and the workers are busy {utilisation:.0%} of the job: efficiency {worst['efficiency']:.2f} ≈ "
             f"{utilisation:.2f} / {inflation:.2f}. A task bound by bandwidth as STREAM's triad is would run "
             f"{1 / share:.2f}× as long with {near} cores streaming at once (each gets {share:.2f} of the bandwidth "
             f"one core gets alone). The job moves about {gbs:.1f} GB/s ({source}) against "
             f"{res[near]['triad_gb_s']:.0f} GB/s that STREAM's triad sustains with {near} threads "
             f"({gbs / res[near]['triad_gb_s']:.0%}). ")
    limit += ("**Bandwidth is the limit here**, as the paper found: the tasks slow down about as much as a "
              "bandwidth-bound kernel would, and the job's traffic approaches what the memory delivers." if bound else
              f"**Bandwidth is not the limit here.** The tasks slow down far less than a bandwidth-bound kernel would "
              f"({inflation:.2f}× against {1 / share:.2f}×)"
              + (", and the job uses a small part of the bandwidth" if gbs < 0.5 * res[near]["triad_gb_s"] else "")
              + f". What remains is the {1 - utilisation:.0%} of worker time spent idle (waiting for work or "
              f"messages) and the tasks' own {inflation:.2f}× time when every core is busy.")
    sound = list(checks.values()) + [render_check]
    ok = all(c["topology"]["manifold"] and c["topology"]["oriented"] and not c["topology"]["degenerate_triangles"]
             and not c.get("violations") for c in sound)
    summary.append(f"Topology: {len(sound)} surface(s) checked, " + (
        "all manifold, consistently oriented, without degenerate triangles." if ok else
        "**some unsound: see the table.**"))

    triangles = []
    for d in series:
        reports = [x for r in rows if r["domains"] == d for x in r["reports"]]
        raw, tri = reports[0]["raw_triangles"], reports[0]["triangles"]
        same = len({(x["raw_triangles"], x["triangles"]) for x in reports}) == 1
        hashes = {x["surface_sha256"] for x in reports if "surface_sha256" in x}
        triangles.append([d, f"{raw:,}", f"{tri:,}" + ("" if same else " (differs between runs!)"),
                          f"{raw / tri:.1f}×", f"{len(hashes)} of {len(reports)} runs" if hashes else "not recorded"])
    check_rows = []
    for d, c in sorted(checks.items(), reverse=True):
        t = c["topology"]
        counts = Counter(f"genus {s['genus']}, {s['boundary_loops']} boundary loops"
                         + ("" if s["orientable"] else ", not orientable") for s in t["signatures"])
        check_rows.append([d, f"{t['triangles']:,}", t["components"],
                           "; ".join(f"{n} × ({text})" if n > 1 else text for text, n in counts.items()),
                           "yes" if t["manifold"] else "**no**",
                           f"{t['non_manifold_edges']} / {t['non_manifold_vertices']}",
                           "yes" if t["oriented"] else "**no**", t["degenerate_triangles"],
                           f"{t['min_angle_deg']['below_1']:,}", f"{t['min_angle_deg']['min']:.3g}°",
                           "not counted" if c.get("self_intersections") is None else c["self_intersections"],
                           "not recorded" if c.get("violations") is None else
                           "clean" if not c["violations"] else "; ".join(c["violations"])])

    fig, ax = figure(6.4, 5.4)
    top = max(16, max(r["workers"] for r in rows) + 1)
    ax.plot([0, top], [0, top], "k--", linewidth=1, label="ideal")
    for domains, marker in zip(series, "osd^v"):
        ax.plot(*zip(*sorted((r["workers"], r["speedup"]) for r in rows if r["domains"] == domains)), marker=marker,
                label=f"{domains} domains")
    ax.set(xlabel="working MPI processes", ylabel="speed-up T(1) / T(P)", xlim=(0, top), ylim=(0, top))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    ax.set_title(f"Speed-up of the isosurface job, N = {meta['lattice']} (cf. the paper's Fig. 11)", fontsize=10)
    save(fig, folder / "speedup.png", stamp)
    fig, ax = figure(6.4, 4.6)
    base = stream["results"][0]
    for kind, style in (("triad", "k-"), ("copy", "k:")):
        ax.plot([r["threads"] for r in stream["results"]],
                [r[f"{kind}_gb_s"] / r["threads"] / base[f"{kind}_gb_s"] for r in stream["results"]], style,
                label=f"STREAM {kind}: bandwidth per thread / 1 thread's")
    for domains, marker in zip(series, "osd^v"):
        ax.plot(*zip(*sorted((r["workers"], r["efficiency"]) for r in rows if r["domains"] == domains)),
                marker=marker, label=f"job efficiency, {domains} domains")
    ax.set(xlabel="threads (STREAM) / working MPI processes (job)", ylabel="fraction of the one-core rate",
           ylim=(0, 1.1))
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", fontsize=7)
    ax.set_title("Job efficiency against each core's share of memory bandwidth", fontsize=10)
    save(fig, folder / "bandwidth.png", stamp + "; STREAM: bench/bench_stream.cpp")
    return dict(
        meta=meta, sources=sources, machine=machine, dates=dates, stream=stream, render=render,
        render_check=render_check, topology_summary=topology_summary, bullets=bullets,
        cpu_only=all("--device cpu" in s["command"] for s in sources) or all("device" not in r["report"]
                                                                             for r in data["runs"]),
        calls=[m[1] for m in (re.search(r"--points (\S+)", s["command"]) for s in sources) if m],
        render_counts=sorted({x["triangles"] for r in rows if r["domains"] == render["domains"] for x in r["reports"]}),
        summary=bullets(summary), limit=limit,
        speedup=table(["domains", "working processes P", "runs", "job s", "speed-up", "efficiency", "worker peak MiB"],
                      speedup),
        stages=table(["domains", "P", "generate", "extract", "reduce (domains)", "seams (all stages)", "busy", "idle"],
                     stages),
        triangles=table(["domains", "raw triangles", "reduced triangles", "ratio", "distinct hashes"], triangles),
        checks=table(["domains", "triangles", "components", "signature", "manifold", "non-manifold edges / vertices",
                      "consistently oriented", "degenerate", "angles < 1°", "smallest angle", "self-intersections",
                      "`check --strict`"],
                     check_rows),
        # A check made apart from the sweep (a later commit's surface, the
        # same bytes for any rank count) says where it comes from.
        check_sources="".join(f"\n{source}\n" for source in sorted({c["source"] for c in checks.values()
                                                                        if "source" in c})),
        factors=table(["domains", "P", "efficiency", "task inflation", "utilisation"], factors),
        bandwidth=table(["threads", "copy GB/s", "triad GB/s", "triad per thread / 1 thread's"],
                        [[t, f"{x['copy_gb_s']:,.1f}", f"{x['triad_gb_s']:,.1f}",
                          f"{x['triad_gb_s'] / t / res[min(res)]['triad_gb_s']:.2f}"] for t, x in sorted(res.items())]))


def soundness(folder):
    """tools/soak.py's campaigns: every campaign*.json of the folder (the current code's), every
    earlier-campaign*.json (before the reduction's contact test), and regressions.json (the earlier
    campaigns' failures run again with the contact test)."""
    campaigns = [json.loads(p.read_text()) for p in sorted(folder.glob("campaign*.json"))]
    records = [dict(r, seed=c["seed"]) for c in campaigns for r in c["records"]]
    earlier = [json.loads(p.read_text()) for p in sorted(folder.glob("earlier-campaign*.json"))]
    earlier_records = [dict(r, seed=c["seed"]) for c in earlier for r in c["records"]]
    earlier_failed = [r for r in earlier_records if r["outcome"] != "clean"]
    regressions = load(folder, "regressions.json")
    rerun = {(r["seed"], r["index"]): r["outcome"] for r in regressions["records"]}
    outcomes = Counter(r["outcome"] for r in records)
    kinds = Counter((r["kind"], r["level_kind"]) for r in records)
    sources = Counter("lattice" if "lattice" in r else r["mesh"] for r in records)
    failed = [r for r in records if r["outcome"] != "clean"]
    before = load(folder, "before-fix.json")
    before_failed = [r for r in before["records"] if r["outcome"] != "clean"]
    before_reduced = [r for r in before_failed if any(not v.startswith("raw: ") for v in r.get("violations", []))
                      and "--no-reduce" not in r["kind"] and r["kind"] != "extract"]
    triage = load(folder, "triage.json")
    checked = [t for t in triage["failures"] if t["outcome"] == "violations"]

    def defects(c):
        return f"{c['self_intersections']} / {c['zero_area_triangles']} / {c['duplicate_positions']}"

    def dirty(c):
        return bool(c["self_intersections"] or c["zero_area_triangles"] or c["duplicate_positions"])
    # Before: the paper's 250-domain surface as results/paper-reproduction
    # checked it before the node clearance (kept here, since that page now
    # checks later commits' surfaces).
    paper, paper_before = load(folder, "paper-d250-check.json"), load(folder, "paper-d250-before-check.json")
    # The same job after the reduction learned to merge the clearance's
    # clusters, with tools/near_degenerate.py's census of what stays.
    slivers = load(folder, "paper-d250-near-degenerate.json")

    def census_table(rows):
        return table(["shortest edge", "its ends", "where", "triangles under 1°"],
                     [[r["scale"], r["node"], r["border"], r["triangles"]] for r in rows])
    return dict(
        slivers=slivers, slivers_summary=topology_summary(slivers["check"]),
        slivers_census=census_table(slivers["census"]),
        paper=paper, paper_before=paper_before, paper_summary=topology_summary(paper),
        triage=triage, triage_table=table(
            ["seed: job", "before the clearance: crossing pairs / zero-area / repeated positions", "after"],
            [[f"{t['seed']}: {t['index']}", defects(t["before"]), defects(t["after"])] for t in checked]),
        triaged=len(checked), old_too=sum(dirty(t["before"]) for t in checked),
        new_ones=" and ".join(f"{t['seed']}: {t['index']}" for t in checked if not dirty(t["before"])),
        driver_errors=", ".join(f"{t['seed']}: {t['index']}" for t in triage["failures"] if t["outcome"] == "error"),
        before=before, before_failed=len(before_failed), before_reduced=len(before_reduced),
        before_examples=bullets(f"job {r['index']} (`{r['kind']}`): {r['violations'][0]}" for r in before_reduced[:3]),
        jobs=len(records), clean=outcomes.get("clean", 0), failed=len(failed), campaigns=campaigns,
        earlier_jobs=len(earlier_records), regressions=regressions,
        earlier_outcomes=", ".join(f"{n:,} {k}" for k, n in sorted(Counter(r["outcome"] for r in earlier_records).items())),
        earlier_commits=", ".join(sorted({c["commit"][:7] for c in earlier})),
        rerun_clean=sum(o == "clean" for o in rerun.values()), rerun_count=len(rerun),
        earlier_table=table(["seed: job", "command", "outcome", "what", "to reproduce", "with the contact test"],
                            [[f"{r['seed']}: {r['index']}", f"`{r['kind']}`", r["outcome"],
                              "; ".join(r.get("violations", [])) or r.get("detail", ""),
                              "<br>".join(f"`{c}`" for c in r["reproduce"]),
                              rerun.get((r["seed"], r["index"]), "not run again")] for r in earlier_failed]),
        earlier_provenance=bullets(f"`{c['command']}` (written as {c['command'].split('--json ')[-1]}, now "
                                   f"earlier-{c['command'].split('--json ')[-1].split('/')[-1]}): {c['jobs']:,} jobs "
                                   f"in {c['seconds'] / 60:.1f} min; commit {c['commit']}; started {c['started']}; "
                                   f"{c['machine']}" for c in earlier),
        outcomes=", ".join(f"{n:,} {k}" for k, n in sorted(outcomes.items())),
        kinds_table=table(["command", "level", "jobs"],
                          [[f"`{k}`", lv, f"{n:,}"] for (k, lv), n in sorted(kinds.items())]),
        sources=", ".join(f"{n:,} on {k}" for k, n in sorted(sources.items())),
        largest=max((r.get("lattice", 0) for r in records), default=0),
        failures_table=table(["seed: job", "command", "outcome", "what", "to reproduce"],
                             [[f"{r['seed']}: {r['index']}", f"`{r['kind']}`", r["outcome"],
                               "; ".join(r.get("violations", [])) or r.get("detail", ""),
                               "<br>".join(f"`{c}`" for c in r["reproduce"])] for r in failed]) if failed else "",
        provenance=bullets(f"`{c['command']}`: {c['jobs']:,} jobs in {c['seconds'] / 60:.1f} min; commit "
                           f"{c['commit']}; started {c['started']}; {c['machine']}" for c in campaigns))


def insitu(folder):
    """tools/bench_insitu.sh: every runs-N.json of the folder, N ascending."""
    runs = sorted((json.loads(f.read_text()) for f in folder.glob("runs-*.json")), key=lambda r: r["n"])
    rows, stages = [], []
    for r in runs:
        calls, med = r["insitu"]["calls"], statistics.median
        call, call_cpu = med(c["wall"] for c in calls), med(c["cpu"] for c in calls)
        write, read = r["write"], r["read"]
        run, run_cpu = med(x["wall"] for x in r["run"]), med(x["cpu"] for x in r["run"])
        file_wall = write["seconds"] + run + med(read["seconds"])
        file_cpu = write["cpu"] + run_cpu + med(read["cpu"])
        rows.append([f"{r['n']}³", r["ranks"], f"{calls[0]['session']:.2f}", f"{call:.2f} ({call_cpu:.2f})",
                     f"{write['seconds']:.2f} ({write['cpu']:.2f})", f"{run:.2f} ({run_cpu:.2f})",
                     f"{med(read['seconds']):.3f}", f"{file_wall:.2f} ({file_cpu:.2f})",
                     f"**{file_wall / call:.2f}×** ({file_cpu / call_cpu:.2f}×)", f"{write['bytes'] / 2**30:.2f}",
                     "yes" if r["same_bytes"] else "**no**"])
        for q, rank in enumerate(calls[-1]["ranks"]):
            stages.append([f"{r['n']}³", q] + [f"{rank[k]:.2f}" for k in ("check", "scan", "pool", "domain", "seams",
                                                                         "write", "total")]
                          + [f"{int(rank['tetrahedra']):,}", f"{int(rank['extracted']):,}", f"{int(rank['reduced']):,}",
                             f"{int(rank['bytes_sent']):,}"])
    return dict(runs=runs, same=all(r["same_bytes"] for r in runs),
                comparison=table(["lattice", "ranks", "session s", "call s (median)", "write .pvtu s",
                                  "tetiso run s (median)", "read surface s", "file route s", "file route / call",
                                  ".pvtu GiB", "same bytes"], rows),
                stages=table(["lattice", "rank", "check", "scan", "pool", "domain", "seams", "write", "total",
                              "tetrahedra", "triangles extracted", "after reduction", "bytes sent"], stages),
                provenance=bullets([f"`{r['command']}`: commit `{r['commit']}`, {r['machine']}, load average before "
                                    f"{r['load_before']}, {r['date']}" for r in runs]))


def python_binding(folder):
    data = load(folder, "runs.json")
    cases = {c["name"]: c for c in data["cases"]}
    median = {name: statistics.median(c["seconds"]) for name, c in cases.items()}

    def micro(seconds):
        return f"{seconds * 1e6:,.2f}" if seconds < 1e-3 else f"{seconds * 1e6:,.0f}"
    machine = data["machine"]
    return dict(
        data=data, median=median,
        cases_table=table(["call", "median µs", "fastest µs", "calls per batch", "batches"],
                          [[c["label"], micro(median[c["name"]]), micro(min(c["seconds"])), f"{c['calls_per_batch']:,}",
                            len(c["seconds"])] for c in data["cases"]]),
        machine=f"{machine['cpu_model']}, {machine['cpus']} CPUs, {machine['memory']}, {machine['kernel']}")


PAGES = {
    "insitu": (insitu, "insitu", "insitu/README.md"),
    "paper-reproduction": (paper_reproduction, "paper-reproduction", "paper-reproduction.md"),
    "hardware-comparison": (hardware_comparison, "hardware-comparison", "hardware-comparison/README.md"),
    "reduce-gpu": (reduce_gpu, "reduce-gpu", "reduce-gpu/README.md"),
    "gpu-streams": (gpu_streams, "gpu-streams", "gpu-streams/README.md"),
    "reduce-batch": (reduce_batch, "reduce-batch", "reduce-batch/README.md"),
    "extract-gpu": (extract_gpu, "extract-gpu", "extract-gpu/README.md"),
    "scale": (scale, "scale", "scale/README.md"),
    "fuzz": (fuzz, "fuzz", "fuzz/README.md"),
    "soundness": (soundness, "soundness", "soundness/README.md"),
    "solver-read": (solver_read, "solver-read", "solver-read/README.md"),
    "mesh": (mesh, "mesh", "mesh/README.md"),
    "reduce": (reduce, "reduce", "reduce/README.md"),
    "extract": (extract, "extract", "extract/README.md"),
    "python-binding": (python_binding, "python-binding", "python-binding/README.md"),
}
