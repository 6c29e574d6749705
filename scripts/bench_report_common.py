#!/usr/bin/env python3
"""What the benchmark reports share (scripts/report_*.py), and the meta.json
writer for the benchmark drivers (scripts/bench_*.sh).

As a library: reading Google Benchmark aggregates, number formatting, Markdown
tables, and the "Command, machine, commit" section that closes a report.

As a command:
  bench_report_common.py meta OUT.json key=value...
writes OUT.json with the given keys (the run's own facts: commands, source,
commit, load, environment) and the machine's: CPU model and counts, memory,
kernel, compiler, date. Python standard library only.
"""
import json
import os
import re
import subprocess
import sys
from datetime import datetime, timezone
from pathlib import Path


def to_ms(value, unit):
    return value * {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[unit]


def mega(value):
    return f"{value / 1e6:.2f}"


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def load_aggregates(path, name_pattern, key):
    """Google Benchmark aggregates of every case whose run_name matches.

    Returns (context, cases): cases maps key(match) to a dict with the median
    row ("median", counters included), the median and fastest repetition's
    real time in ms ("time_ms", "min_ms") and the coefficient of variation of
    the real time as a fraction ("cv"). Google Benchmark appends "/real_time"
    to the names of real-time cases, so name_pattern should allow it.
    """
    data = json.loads(path.read_text())
    cases = {}
    for row in data["benchmarks"]:
        match = re.match(name_pattern, row.get("run_name", ""))
        if not match or row.get("run_type") != "aggregate":
            continue
        case = cases.setdefault(key(match), {})
        aggregate = row["aggregate_name"]
        if aggregate == "median":
            case["median"] = row
            case["time_ms"] = to_ms(row["real_time"], row["time_unit"])
        elif aggregate == "min":
            case["min_ms"] = to_ms(row["real_time"], row["time_unit"])
        elif aggregate == "cv":
            case["cv"] = row["real_time"]  # a fraction for the cv aggregate
    return data.get("context", {}), cases


def machine_lines(meta, context):
    """The Markdown list items after a report's command: source, commit,
    machine, compiler, libraries, environment, date and load, harness."""
    lines = []
    if meta:
        lines += [f"- Source: {meta['source_state']}",
                  f"- Commit: `{meta['commit']}`",
                  f"- Machine: {meta['cpu_model']}, {meta['cpus']} CPUs available "
                  f"({meta['cores_per_socket']} cores per socket, {meta['threads_per_core']} thread(s) per core), "
                  f"{meta['memory']}, {meta['kernel']}",
                  f"- Compiler: {meta['compiler']}, Release (-O3), "
                  f"`{meta.get('compile_options', '-ffp-contract=off')}`"]
        if meta.get("libraries"):
            lines.append(f"- Libraries: {meta['libraries']}")
        lines += [f"- Environment: `{meta.get('environment', '')}`",
                  f"- Date: {meta['date']}; load average (1, 5, 15 min) before the run {meta['load_before']}, "
                  f"after {meta['load_after']}"]
    if context:
        lines.append(f"- Google Benchmark: {context.get('num_cpus', '?')} CPUs at {context.get('mhz_per_cpu', '?')} "
                     f"MHz, library built as {context.get('library_build_type', '?')} (the harness only; it adds "
                     "nothing measurable to millisecond-long iterations)")
    return lines


def command_section(meta, context, regenerate):
    """The "Command, machine, commit" section that closes a report: the
    driver's command and what it ran (meta's bench_cmd, then its memory_cmds
    where it has any), machine_lines, and how the numbers were taken.
    regenerate is the report script's own command line, which rewrites the
    README from the JSON alone."""
    lines = ["## Command, machine, commit", ""]
    if meta:
        ran = [meta["bench_cmd"], *meta.get("memory_cmds", [])]
        lines += [f"- Command: `{meta['script_cmd']}`, which ran", "", "  ```"]
        lines += [f"  {cmd}" for cmd in ran] + ["  ```", ""]
    lines += machine_lines(meta, context)
    lines += ["", "The machine is shared with other work, so single runs vary: repetitions of all cases are "
              "interleaved in random order, and the medians, fastest repetitions and coefficients of variation "
              f"(cv) are reported. Regenerate with the command above; `{regenerate}` rewrites this file from the "
              "JSON alone.", ""]
    return lines


def stamp(fig, text):
    """Writes a figure's provenance (command, machine, commit, date) small
    along its bottom edge, so that the picture says where it comes from even
    away from its page; the plot area is shrunk to leave it room."""
    fig.text(0.01, 0.005, text, fontsize=6, color="0.35")
    fig.tight_layout(rect=(0, 0.03 + 0.02 * text.count("\n"), 1, 1))


def bench_stamp(meta):
    """stamp()'s text for a benchmark driver's meta.json."""
    return (f"{meta['script_cmd']}; commit {meta['commit'][:12]}; {meta['date']}\n"
            f"{meta['cpu_model']}, {meta['cpus']} CPUs, {meta['kernel']}")


def load_meta(folder):
    """A results folder's meta.json: how its data files were made (command,
    machine, commit, date), for pages whose data files do not say it."""
    return json.loads((Path(folder) / "meta.json").read_text())


def provenance_section(meta, regenerate):
    """The "Command, machine, commit, date" section of a page built from a
    meta.json: one item per run it lists, then how to rewrite the page."""
    lines = ["## Command, machine, commit, date", ""]
    for run in meta["runs"]:
        lines.append(f"- {run['what']}: `{run['command']}`; commit {run['commit']}; {run['date']}; "
                     f"files: {', '.join(f'`{f}`' for f in run['files'])}")
    lines += [f"- Machine: {meta['machine']}", "",
              f"`{regenerate}` rewrites this page from the files named above.", ""]
    return lines


def topology_summary(check):
    """One table cell from `tetiso check` JSON: components and signatures,
    then what would make the surface unsound."""
    t = check["topology"]
    signatures = "; ".join(f"genus {s['genus']}, {s['boundary_loops']} boundary loops"
                           for s in t["signatures"])
    closed = ", closed" if t.get("closed") else ""
    return (f"{t['components']} component{'s' if t['components'] != 1 else ''}, {signatures}{closed}; "
            f"non-manifold {t['non_manifold_edges']} / {t['non_manifold_vertices']}, misoriented "
            f"{t['misoriented_edges']}, degenerate {t['degenerate_triangles']}, duplicate positions "
            f"{t['duplicate_positions']}")


def _run(command):
    try:
        return subprocess.run(command, capture_output=True, text=True, check=False).stdout
    except OSError:
        return ""


def _lscpu(field):
    match = re.search(rf"^{re.escape(field)}:\s*(.*)$", _run(["lscpu"]), re.MULTILINE)
    return match.group(1).strip() if match else "?"


def machine_facts():
    memory_kib = 0
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal:"):
                memory_kib = int(line.split()[1])
    uname = os.uname()
    compiler = _run(["c++", "--version"]).splitlines()
    return {
        "cpu_model": _lscpu("Model name"),
        "cpus": str(len(os.sched_getaffinity(0))),  # as nproc counts them
        "cores_per_socket": _lscpu("Core(s) per socket"),
        "threads_per_core": _lscpu("Thread(s) per core"),
        # As `free -g` prints it, which is what bench_extract.sh records.
        "memory": f"{memory_kib // 2**20} GiB",
        "kernel": f"{uname.sysname} {uname.release}",
        "compiler": compiler[0] if compiler else "?",
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    }


def main(argv):
    if len(argv) < 2 or argv[0] != "meta" or any("=" not in arg for arg in argv[2:]):
        sys.exit("usage: bench_report_common.py meta OUT.json key=value...")
    meta = dict(arg.split("=", 1) for arg in argv[2:])
    meta.update(machine_facts())
    with open(argv[1], "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1:])
