"""The specs of the GPU pages (results/reduce-gpu, hardware-comparison,
gpu-streams) for tools/render_results.py, apart from results_pages.py's
others: each takes its folder and returns the names its page.md uses."""
import gzip
import json
import re
import statistics
from collections import Counter

from render_results import plot_timeline, figure, load, load_aggregates, save, table



BYTES_PER_TRIANGLE_ROUND = 12 + 6 + 36 + 18 + 32 + 8 + 37 + 12 + 24 + 16
READS_BACK = ("get", "count", "exclusive_scan", "filter", "rank", "copy_if")  # wait for the device
LAUNCHES = ("for_each", "for_each_of", "assign", "set")


def reduce_gpu(folder, n=100):
    meta = load(folder, "meta.json")
    pattern = (r"^(reduce/(?P<who>gpu|tetiso|meshopt)/N:(?P<n>\d+)(/threads:(?P<threads>\d+))?|domain/(?P<dwho>gpu|"
               r"tetiso)/N:(?P<dn>\d+)/D:(?P<dd>\d+)|copy/gpu)(/repeats:\d+)?(/manual_time|/real_time)?$")
    _, cases = load_aggregates(folder / "bench_reduce_gpu.json", pattern, lambda m: (
        ("reduce", m["who"], int(m["n"]), int(m["threads"] or 0)) if m["who"] else
        ("domain", m["dwho"], int(m["dn"]), int(m["dd"])) if m["dwho"] else ("copy", "gpu", 0, 0)))
    rounds = load(folder, "rounds_n100.json")["rounds"]
    gpu = cases["reduce", "gpu", n, 0]
    gpu_s, tris_in = gpu["time_ms"] / 1e3, gpu["median"]["triangles_in"]
    threads = max(k[3] for k in cases if k[:3] == ("reduce", "tetiso", n))
    dkey = next(k for k in cases if k[:2] == ("domain", "gpu"))
    dgpu, dcpu = cases[dkey], cases[("domain", "tetiso") + dkey[2:]]

    def ms(seconds):
        return f"{seconds * 1e3:,.1f}" if seconds < 10 else f"{seconds * 1e3:,.0f}"

    def row(label, where, c, base, rate=True):  # base: the GPU's case it is compared with
        s = c["time_ms"] / 1e3
        return ([label, where, ms(s), ms(c["min_ms"] / 1e3)] + ([f"{tris_in / s / 1e6:.2f}"] if rate else [])
                + ["1.00×" if c is base else f"{s / (base['time_ms'] / 1e3):.1f}×"])

    profile = (folder / "profile_n100.txt").read_text()
    sites = [(float(ms_), int(calls), f"{what} at {where}") for ms_, calls, what, where in
             re.findall(r"^\s+([\d.]+) ms\s+(\d+) calls\s+(\S+) (\S+)$", profile, re.MULTILINE)]
    bandwidth = cases["copy", "gpu", 0, 0]["median"]["GB/s"] * 1e9
    triangle_rounds = sum(r["triangles"] for r in rounds)
    tail = sorted(r["seconds"] for r in rounds if r["candidates"] < 5000)  # rounds with almost nothing to test

    fig, ax = figure(7, 3.6)
    xs = [r["round"] for r in rounds]
    ax.bar(xs, [r["seconds"] * 1e3 for r in rounds], color="#3b6ea5")
    ax.set_xlabel("round")
    ax.set_ylabel("ms on the GPU")
    ax2 = ax.twinx()
    ax2.plot(xs, [r["triangles"] / 1e6 for r in rounds], color="#c0504d", marker=".")
    ax2.set_ylabel("triangles at the round's start (M)", color="#c0504d")
    ax.set_title(f"N = {n} paper surface on {meta['gpu'].split(',')[0]}: time and size per round")
    save(fig, folder / "rounds.png")
    return dict(
        meta=meta, n=n, gpu=gpu, gpu_s=gpu_s, tris_in=tris_in, rounds=rounds, ms=ms, target_s=tris_in / 50e6,
        dkey=dkey, dgpu=dgpu, dgpu_s=dgpu["time_ms"] / 1e3, bandwidth=bandwidth, triangle_rounds=triangle_rounds,
        bytes_per_triangle=BYTES_PER_TRIANGLE_ROUND, floor_bytes=triangle_rounds * BYTES_PER_TRIANGLE_ROUND,
        floor_s=triangle_rounds * BYTES_PER_TRIANGLE_ROUND / bandwidth, fixed=tail[len(tail) // 2],
        reads=sum(c for _, c, site in sites if site.split(" ")[0] in READS_BACK) / len(rounds),
        launches=sum(c for _, c, site in sites if site.split(" ")[0] in LAUNCHES) / len(rounds),
        sorts=sum(t for t, _, site in sites if site.startswith(("order_by_priority", "group_by_key"))),
        profile_s=float(re.search(r"tetiso GPU profile: ([\d.]+) s", profile).group(1)),
        reduction=table(["", "where", "median ms", "fastest ms", "M input triangles/s", "time / GPU's"],
                        [row("tetiso, GPU", "1 GPU", gpu, gpu),
                         row("tetiso, CPU", "1 thread", cases["reduce", "tetiso", n, 1], gpu),
                         row("tetiso, CPU", f"{threads} threads", cases["reduce", "tetiso", n, threads], gpu),
                         row("meshoptimizer (no topology kept)", "1 thread", cases["reduce", "meshopt", n, 1], gpu)]),
        domain=table(["", "where", "median ms", "fastest ms", "time / GPU's"],
                     [row("tetiso, GPU", "1 GPU", dgpu, dgpu, False), row("tetiso, CPU", "1 core", dcpu, dgpu, False)]),
        heaviest=table(["ms", "calls", "primitive at"], [[f"{t:.1f}", c, f"`{site}`"] for t, c, site in sites[:10]]),
        shown=lambda command: re.sub(r"/\S*/(?=[a-z_0-9]+\.json)", "OUT/", command),
        **reduce_gpu_before_after(folder, n))


NCU_UNITS = {"byte": 1, "Kbyte": 1e3, "Mbyte": 1e6, "Gbyte": 1e9, "ns": 1e-6, "us": 1e-3, "ms": 1, "s": 1e3}


def ncu_kernels(path):
    """The kernels of an Nsight Compute log with the metrics the page compares:
    a short name, the grid, ms, active threads a warp, local-memory bytes
    loaded and stored, DRAM bytes."""
    kernels = []
    for block in re.split(r"\n(?=  void )", path.read_text())[1:]:
        head = block.splitlines()[0]
        template = re.match(r"  void (?:\w+::)*(\w+)<", head)
        instance = re.search(r"\[lambda\(long\) \(instance (\d+)\)\]", head)
        grid = re.search(r"\((\d+), 1, 1\)x\(", head)
        metric = {name: float(value.replace(",", "")) * NCU_UNITS[unit] for name, unit, value in
                  re.findall(r"^\s+(\S+)\s+(byte|Kbyte|Mbyte|Gbyte|ns|us|ms|s)\s+([\d.,]+)$", block, re.MULTILINE)}
        ratio = re.search(r"smsp__thread_inst_executed_per_inst_executed\.ratio\s+([\d.]+)", block)
        kernels.append(dict(
            name=f"{template[1] if template else '?'}" + (f", lambda {instance[1]}" if instance else ""),
            grid=int(grid[1]) if grid else 0, ms=metric["gpu__time_duration.sum"],
            threads=float(ratio[1]), local_ld=metric["l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum"],
            local_st=metric["l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum"], dram=metric["dram__bytes.sum"]))
    return kernels


def ncu_table(kernels):
    def gb(value):
        return "none" if value == 0 else f"{value / 1e9:.2f}"
    return table(["kernel", "blocks", "ms", "active threads a warp", "local loads GB", "local stores GB", "DRAM GB"],
                 [[f"`{k['name']}`", f"{k['grid']:,}", f"{k['ms']:.2f}", f"{k['threads']:.2f}", gb(k["local_ld"]),
                   gb(k["local_st"]), gb(k["dram"])] for k in kernels])


def reduce_gpu_before_after(folder, n):
    """The commit of the page against the baseline in baseline-*/: the same
    benchmark cases, the fixed cost of a small round, the dry runs' profile."""
    base = next(folder.glob("baseline-*"))
    pattern = r"^(reduce/gpu/N:(\d+)|domain/gpu/N:(\d+)/D:(\d+))(/repeats:\d+)?(/manual_time|/real_time)?$"

    def cases(f):
        return load_aggregates(f / "bench_reduce_gpu.json", pattern, lambda m: m[1])[1]

    def fixed(f):
        tail = sorted(r["seconds"] for r in load(f, "rounds_n100.json")["rounds"] if r["candidates"] < 5000)
        return tail[len(tail) // 2]

    now, before = cases(folder), cases(base)
    rows = [[f"`{name}`, median ms", f"{before[name]['time_ms']:.1f}", f"{now[name]['time_ms']:.1f}",
             f"{now[name]['time_ms'] / before[name]['time_ms']:.2f}"] for name in sorted(now) if name in before]
    rows.append(["a round with < 5,000 candidates (median), ms", f"{fixed(base) * 1e3:.2f}",
                 f"{fixed(folder) * 1e3:.2f}", f"{fixed(folder) / fixed(base):.2f}"])
    return dict(baseline=base.name, baseline_commit=base.name.split("-", 1)[1], fixed_before=fixed(base),
                before_after=table(["", base.name.split("-", 1)[1], "this page", "ratio"], rows),
                ncu_before=ncu_table(ncu_kernels(base / "ncu_dry_run.txt")),
                ncu_after=ncu_table(ncu_kernels(folder / "ncu_dry_run.txt")))


# Issue 41's wall times (seconds.total), by case and run.
HARDWARE_TARGETS = {(500, 125, "auto-g2"): 2.0, (1000, 1000, "auto-g1"): 12.0, (1000, 1000, "auto-g2"): 8.0,
                    (1000, 1000, "auto-g4"): 5.0}


def hardware_mode_key(mode):
    """cpu first, then by GPUs, gpu before auto."""
    if mode == "cpu":
        return (0, 0, 0)
    device, gpus = mode.rsplit("-g", 1)
    return (1, int(gpus), ("gpu", "auto").index(device))


def hardware_mode_name(mode):
    if mode == "cpu":
        return "cpu"
    device, gpus = mode.rsplit("-g", 1)
    return f"{device}, {gpus} GPU{'s' if gpus != '1' else ''}"


def hardware_runs(folder, stem):
    """A case's reports by run (cpu, gpu-gG, auto-gG; an `auto` of one GPU
    from before runs were named by their GPUs is auto-g1) and each run's
    verdict against the CPU's surface."""
    runs = {}
    for path in folder.glob(f"{stem}-*.json.gz"):
        mode = path.name[len(stem) + 1: -len(".json.gz")]
        runs["auto-g1" if mode == "auto" else mode] = json.loads(gzip.decompress(path.read_bytes()))
    verdicts = {}
    for line in (folder / f"{stem}-cmp.txt").read_text().splitlines():
        words = line.split()
        if len(words) == 1:
            verdicts["auto-g1"] = words[0]
        elif words:
            verdicts[words[0]] = words[1]
    return dict(sorted(runs.items(), key=lambda kv: hardware_mode_key(kv[0]))), verdicts


def by_device(report):
    """Per device: tasks, domain task seconds, busy seconds, raw triangles of
    its domain tasks, waits for a grant, summed stage seconds of its domain tasks."""
    rows = {}
    for t in report["tasks"]:
        r = rows.setdefault(t["device"], {"tasks": 0, "domains": [], "busy": 0.0, "triangles": 0, "waits": [],
                                          "stages": Counter()})
        r["tasks"] += 1
        r["busy"] += t["end"] - t["start"]
        r["waits"].append(t.get("wait_seconds", 0.0))
        if t["kind"] == "domain":
            r["domains"].append(t["end"] - t["start"])
            r["triangles"] += t["triangles_in"]
            r["stages"].update(t.get("stage_seconds", {}))
    return sorted(rows.items())


def hardware_comparison(folder):
    meta = load(folder, "meta.json")
    cases = {}
    for path in folder.glob("n*-d*-cpu.json.gz"):
        stem = path.name[: -len("-cpu.json.gz")]
        n, d = (int(part[1:]) for part in stem.split("-"))
        cases[n, d] = hardware_runs(folder, stem)
    cases = dict(sorted(cases.items(), key=lambda kv: (kv[0][0], -kv[0][1])))
    end_to_end, split, stages = [], [], []
    for (n, d), (runs, verdicts) in cases.items():
        cpu_total = runs["cpu"]["seconds"]["total"]
        for mode, report in runs.items():
            sec = report["seconds"]
            target = HARDWARE_TARGETS.get((n, d, mode))
            end_to_end.append([n, d, hardware_mode_name(mode), f"**{sec['total']:.1f}**", f"{sec['job']:.1f}",
                               f"{sec['total'] - sec['job'] - sec['write']:.1f}", f"{cpu_total / sec['total']:.2f}×",
                               "" if mode == "cpu" else verdicts.get(mode, "not compared"),
                               "" if target is None else
                               f"≤ {target:g} s: {'met' if sec['total'] <= target else 'missed'}"])
            seams = sum(t["end"] - t["start"] for t in report["tasks"] if t["kind"] == "seam")
            for device, r in by_device(report):
                if mode != "cpu":
                    split.append([f"{n} / {d}", hardware_mode_name(mode), device, r["tasks"], len(r["domains"]),
                                  f"{r['busy']:.1f}",
                                  f"{100 * r['busy'] / sec['job']:.0f}%" if device != "cpu" else "",
                                  f"{r['triangles'] / 1e6:.1f} M",
                                  f"{statistics.median(r['domains']):.3f}" if r["domains"] else "—",
                                  f"{statistics.mean(r['waits']):.2f}"])
                rate = [f"{r['triangles'] / r['stages'][s] / 1e6:.1f}" if r["stages"][s] else "—"
                        for s in ("generate", "extract", "reduce")]
                stages.append([f"{n} / {d}", hardware_mode_name(mode), device, *rate, f"{seams:.1f}"])

    modes = sorted({m for runs, _ in cases.values() for m in runs}, key=hardware_mode_key)
    fig, ax = figure(7, 3.8)
    width = 0.8 / len(modes)
    for j, mode in enumerate(modes):
        xs = [i - 0.4 + width * (j + 0.5) for i, (runs, _) in enumerate(cases.values()) if mode in runs]
        ys = [runs[mode]["seconds"]["total"] for runs, _ in cases.values() if mode in runs]
        ax.bar(xs, ys, width, label=f"--device {hardware_mode_name(mode)}")
    ax.set_xticks(list(range(len(cases))), [f"N = {n}\n{d} domains" for n, d in cases])
    ax.set_ylabel("seconds from launch to the written surface")
    ax.set_title(f"tetiso run on {meta['cpus']} cores and {meta['gpu'].split(',')[0]}")
    ax.legend(fontsize=7)
    save(fig, folder / "seconds.png", f"{meta['script_cmd']}; commit {meta['commit']}; {meta['date']}\n"
         f"{meta['cpu_model']}, {meta['gpu']}")
    timeline_runs = cases[500, 125][0]
    timeline_mode = max((m for m in timeline_runs if m.startswith("auto")), key=hardware_mode_key)
    report = folder / "timeline-report.json"
    report.write_text(json.dumps(timeline_runs[timeline_mode]))
    plot_timeline(report, folder / "timeline-n500-d125-auto.png")
    report.unlink()
    return dict(
        meta=meta,
        timeline_mode=hardware_mode_name(timeline_mode),
        end_to_end=table(["N", "domains", "--device", "wall s", "job s", "start-up s", "vs cpu", "surface (cmp)",
                          "target (issue 41)"], end_to_end),
        split=table(["N / domains", "--device", "device", "tasks", "domain tasks", "busy s", "GPU busy",
                     "raw triangles", "median domain s", "mean wait s"], split),
        stages=table(["N / domains", "--device", "device", "generate M tris/s", "extract M tris/s", "reduce M tris/s",
                      "seams s (all, CPU)"], stages))


def gpu_streams(folder):
    """bench_gpu_streams: K Devices of one GPU against the host's cores."""
    data, run = load(folder, "gpu_streams.json"), load(folder, "run.json")
    sample = data["rows"][0]

    def cpu_share(k):  # /usr/bin/time -v of that K run alone
        log = folder / "raw" / f"k{k}_time.log"
        found = re.search(r"Percent of CPU this job got: (\d+)%", log.read_text()) if log.exists() else None
        return f"{int(found[1]):,} %" if found else ""

    rows = []
    for r in data["rows"]:
        k = r["streams"]
        gpu = k > 0
        latency = r["warm_s"] * (k if gpu else 16) / data["count"]
        rows.append([k if gpu else "CPU, 16 threads", f"{r['warm_s']:.2f}", f"{r['cold_s']:.2f}" if gpu else "",
                     f"{r['domains_per_s']:.1f}", f"{r['raw_triangles_per_s'] / 1e6:.2f} M",
                     f"{latency * 1e3:,.0f} ms" if latency < 1 else f"{latency:.2f} s",
                     f"{r['buffer_bytes'] / 2**20:,.0f} MiB" if gpu else "",
                     f"{r['device_used_bytes'] / 2**20:,.0f} MiB" if gpu else "", cpu_share(k) if gpu else ""])
    gpus = [r for r in data["rows"] if r["streams"] > 0]
    best = max(gpus, key=lambda r: r["raw_triangles_per_s"])
    return dict(data=data, run=run, sample=sample, best=best, one=gpus[0],
                cpu=next(r for r in data["rows"] if r["streams"] == 0),
                streams=table(["K streams", "warm s", "cold s", "domains/s", "raw triangles/s", "per-task latency",
                               "buffers held", "GPU memory used", "host CPU"], rows))


def reduce_batch(folder):
    """bench_gpu_streams --batches: B domains' pieces reduced side by side, on K streams."""
    data, run = load(folder, "reduce_batch.json"), load(folder, "run.json")
    gpus = [r for r in data["rows"] if r["streams"] > 0]
    cpu = next(r for r in data["rows"] if r["streams"] == 0)
    one = next(r for r in gpus if r["streams"] == 1 and r["batch"] == 1)
    best = max(gpus, key=lambda r: r["raw_triangles_per_s"])
    best_one_stream = max((r for r in gpus if r["streams"] == 1), key=lambda r: r["raw_triangles_per_s"])
    rows = [[r["streams"], r["batch"], f"{r['warm_s']:.2f}", f"{r['cold_s']:.2f}", f"{r['domains_per_s']:.1f}",
             f"{r['raw_triangles_per_s'] / 1e6:.2f} M", f"{r['raw_triangles_per_s'] / one['raw_triangles_per_s']:.2f}×",
             f"{r['buffer_bytes'] / 2**20:,.0f} MiB", f"{r['device_used_bytes'] / 2**20:,.0f} MiB"] for r in gpus]
    cpus = [r for r in data["rows"] if r["streams"] == 0]
    rows += [[f"CPU, {r['name'].split(':')[1].split('/')[0]} threads", r.get("batch", 1), f"{r['warm_s']:.2f}", "",
              f"{r['domains_per_s']:.1f}", f"{r['raw_triangles_per_s'] / 1e6:.2f} M",
              f"{r['raw_triangles_per_s'] / one['raw_triangles_per_s']:.2f}×", "", ""] for r in cpus]
    # nsys: the GPU time of the trace by kernel, grouped by the step of the round it serves.
    groups = Counter()
    total = 0
    with open(folder / "raw" / "nsys_cuda_gpu_kern_sum.csv") as f:
        header = f.readline()
        assert header.startswith("Time (%),Total Time (ns)")
        for line in f:
            nanoseconds = int(line.split(",")[1])
            name = line.split('"')[1] if '"' in line else line.rsplit(",", 1)[1]
            total += nanoseconds
            if "dry_run_all" in name and "for_each_heavy_kernel" in name:
                step = "dry runs: the samples of the leaves placed, one a thread"
            elif "dry_run_all" in name and "for_each_of_heavy_kernel" in name:
                step = "dry runs: geometry of the collapses that passed the first stage"
            elif "dry_run_all" in name:
                step = "dry runs: placement and connectivity of every candidate (first stage)"
            elif "marching" in name or "DeviceScanKernel" in name:
                step = "extraction (marching tetrahedra, its scans)"
            elif "choose_by_reservations" in name or "claim_chosen" in name:
                step = "the choice by reservations"
            elif "order_fans" in name or "build_fans" in name or "group_by_key" in name:
                step = "fans (grouping and ordering)"
            else:
                step = "everything else (edges, geometry, cones, classification, sorts, apply, compaction, samples' sort)"
            groups[step] += nanoseconds
    kernels = table(["step", "GPU time", "share"], [[step, f"{ns / 1e9:.3f} s", f"{100 * ns / total:.1f} %"]
                                                    for step, ns in groups.most_common()])
    concurrency = (folder / "raw" / "nsys_concurrency.txt").read_text()
    busy = float(re.search(r"device busy .*?: ([\d.]+)%", concurrency)[1])
    issue = float(re.search(r"([\d.]+)\s+SM Issue", concurrency)[1])
    dram = float(re.search(r"([\d.]+)\s+DRAM Read", concurrency)[1])
    syncs = re.search(r"([\d.]+) s\s+(\d+) calls\s+([\d.]+) us each\s+cudaStreamSynchronize", concurrency)
    dry_share = 100 * sum(ns for step, ns in groups.items() if step.startswith("dry runs")) / total
    cpu_batched = max(cpus, key=lambda r: r.get("batch", 1))
    host = load(folder, "host_batch.json")
    host_rows = {r.get("batch", 1): r for r in host["rows"] if r["streams"] == 0}
    # Nsight Compute: the dry runs of the first rounds of the B = 64 batch, the longest four of each stage.
    import csv
    import io
    with gzip.open(folder / "raw" / "ncu_b64.csv.gz", "rt") as f:
        lines = list(csv.reader(io.StringIO(f.read())))
    head = lines[0]
    at = {name: head.index(name) for name in ("ID", "Kernel Name", "Metric Name", "Metric Value", "Metric Unit")}
    metrics = {}
    for line in lines[1:]:
        kernel = metrics.setdefault(int(line[at["ID"]]), {"name": line[at["Kernel Name"]]})
        value = line[at["Metric Value"]].replace(",", "")
        if re.fullmatch(r"[\d.]+", value):
            kernel[line[at["Metric Name"]]] = (float(value), line[at["Metric Unit"]])
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}

    def stage(name):
        return ("samples placed" if "for_each_heavy_kernel" in name else
                "geometry (second stage)" if "for_each_of_heavy_kernel" in name else "placement and connectivity")
    ncu_rows = []
    for label in ("placement and connectivity", "geometry (second stage)", "samples placed"):
        ks = sorted((k for k in metrics.values() if stage(k["name"]) == label),
                    key=lambda k: -k["Duration"][0] * scale[k["Duration"][1]])[:4]
        for k in sorted(ks, key=lambda k: -k["Duration"][0] * scale[k["Duration"][1]]):
            ncu_rows.append([label, f"{k['Duration'][0] * scale[k['Duration'][1]]:.1f}", f"{k['Grid Size'][0]:,.0f}",
                             f"{k['smsp__thread_inst_executed_per_inst_executed.ratio'][0]:.1f}",
                             f"{k['Achieved Occupancy'][0]:.0f} %", f"{k['Compute (SM) Throughput'][0]:.0f} %",
                             f"{k['DRAM Throughput'][0]:.0f} %",
                             f"{k['l1tex__t_bytes_pipe_lsu_mem_local_op_ld.sum'][0] / 1e9:.0f} / "
                             f"{k['l1tex__t_bytes_pipe_lsu_mem_local_op_st.sum'][0] / 1e9:.0f} GB"])
    ncu = table(["dry-run stage", "ms", "blocks", "active threads per warp", "achieved occupancy", "SM throughput",
                 "DRAM throughput", "local memory loads / stores"], ncu_rows)
    return dict(data=data, run=run, best=best, best_one_stream=best_one_stream, one=one, cpu=cpu,
                cpu_batched=cpu_batched, host=host, host_rows=host_rows, run_host=load(folder, "run_host_batch.json"),
                run_ncu=load(folder, "run_ncu.json"), ncu=ncu, busy=busy,
                issue=issue, dram=dram, sync_calls=int(syncs[2]), dry_share=dry_share, kernels=kernels,
                concurrency=concurrency, batches=table(["K streams", "B domains a batch", "warm s", "cold s",
                                                        "domains/s", "raw triangles/s", "against K = 1, B = 1",
                                                        "buffers held", "GPU memory used"], rows))
