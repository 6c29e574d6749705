#!/usr/bin/python3
"""Renders the results pages from their data: results/NAME/page.md (the prose,
written by hand) with its placeholders filled from the folder's JSON files by
NAME's spec in tools/results_pages.py, or results_pages_gpu.py for the GPU
pages (which data, which tables and plots, which derived figures).

    tools/render_results.py [--results DIR] [NAME...]
        NAME: a page (default: every page); DIR: a results folder other than
        the repository's (a copy, say).

A placeholder is {{ expression }} or {{ expression | format }}, a Python
expression over the names the spec returns, formatted with format() when a
format is given. Every number on a page comes from the data in its folder; a
page names the command, machine, commit and date its data record. Debian's
python3 with python3-matplotlib (for the plots).
"""
import json
import re
import subprocess
import sys
from pathlib import Path

RESULTS = Path(__file__).resolve().parent.parent / "results"
PLACEHOLDER = re.compile(r"\{\{(.*?)\}\}", re.DOTALL)


def fill(template, names, where):
    def value(match):
        expression, _, spec = match.group(1).rpartition("|") if re.search(
            r"\|\s*[^\s|'\"()]*\s*$", match.group(1)) else (match.group(1), "", "")
        try:
            return format(eval(expression.strip(), dict(names)), spec.strip())
        except Exception as error:
            sys.exit(f"{where}: {{{{{match.group(1)}}}}}: {error!r}")
    return PLACEHOLDER.sub(value, template)


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return "\n".join(lines + ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows])


def bullets(items):
    return "\n".join(f"- {item}" for item in items)


def load(folder, name):
    path = Path(folder) / name
    return json.loads(path.read_text()) if path.exists() else None


def to_ms(value, unit):
    return value * {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[unit]


def load_aggregates(path, name_pattern, key):
    """Google Benchmark aggregates of every case whose run_name matches:
    (context, {key(match): {"median": row, "time_ms", "min_ms", "cv"}}), the
    times of the median and fastest repetitions, the cv as a fraction."""
    data = json.loads(Path(path).read_text())
    cases = {}
    for row in data["benchmarks"]:
        match = re.match(name_pattern, row.get("run_name", ""))
        if not match or row.get("run_type") != "aggregate":
            continue
        case = cases.setdefault(key(match), {})
        aggregate = row["aggregate_name"]
        if aggregate == "median":
            case["median"], case["time_ms"] = row, to_ms(row["real_time"], row["time_unit"])
        elif aggregate == "min":
            case["min_ms"] = to_ms(row["real_time"], row["time_unit"])
        elif aggregate == "cv":
            case["cv"] = row["real_time"]
    return data.get("context", {}), cases


def bench_provenance(meta, context):
    """The list that closes a benchmark page (results/extract, results/reduce):
    the driver's command and what it ran, then source, machine and date from
    the meta.json that tools/bench_meta.py wrote."""
    ran = "\n".join(f"  {cmd}" for cmd in [meta["bench_cmd"], *meta.get("memory_cmds", [])])
    lines = [f"- Command: `{meta['script_cmd']}`, which ran", "", "  ```", ran, "  ```", "",
             f"- Source: {meta['source_state']}", f"- Commit: `{meta['commit']}`",
             f"- Machine: {meta['cpu_model']}, {meta['cpus']} CPUs available ({meta['cores_per_socket']} cores per "
             f"socket, {meta['threads_per_core']} thread(s) per core), {meta['memory']}, {meta['kernel']}",
             f"- Compiler: {meta['compiler']}, Release (-O3), `{meta.get('compile_options', '-ffp-contract=off')}`"]
    if meta.get("libraries"):
        lines.append(f"- Libraries: {meta['libraries']}")
    lines += [f"- Environment: `{meta.get('environment', '')}`",
              f"- Date: {meta['date']}; load average (1, 5, 15 min) before the run {meta['load_before']}, "
              f"after {meta['load_after']}",
              f"- Google Benchmark: {context.get('num_cpus', '?')} CPUs at {context.get('mhz_per_cpu', '?')} MHz, "
              f"library built as {context.get('library_build_type', '?')} (the harness only; it adds nothing "
              "measurable to millisecond-long iterations)"]
    return "\n".join(lines)


def runs_provenance(meta):
    """A meta.json's runs, one item each, and the machine."""
    return "\n".join([f"- {run['what']}: `{run['command']}`; commit {run['commit']}; {run['date']}; files: "
                      + ", ".join(f"`{f}`" for f in run["files"]) for run in meta["runs"]]
                     + [f"- Machine: {meta['machine']}"])


def topology_summary(check):
    """One table cell from `tetiso check` JSON."""
    t = check["topology"]
    signatures = "; ".join(f"genus {s['genus']}, {s['boundary_loops']} boundary loops" for s in t["signatures"])
    return (f"{t['components']} component{'s' if t['components'] != 1 else ''}, {signatures}"
            f"{', closed' if t.get('closed') else ''}; non-manifold {t['non_manifold_edges']} / "
            f"{t['non_manifold_vertices']}, misoriented {t['misoriented_edges']}, degenerate "
            f"{t['degenerate_triangles']}, duplicate positions {t['duplicate_positions']}")


def plot_timeline(report, png):
    """scripts/plot_timeline.py, the users' own, draws a job's timeline."""
    script = Path(__file__).resolve().parent.parent / "scripts" / "plot_timeline.py"
    subprocess.run([sys.executable, str(script), str(report), "-o", str(png)], check=True)


def figure(width, height):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt.subplots(figsize=(width, height))


def save(fig, path, stamp=None, dpi=110):
    """Writes a figure; stamp (command, machine, commit, date) goes small along
    its bottom edge, so that the picture says where it comes from."""
    import matplotlib.pyplot as plt
    if stamp:
        fig.text(0.01, 0.005, stamp, fontsize=6, color="0.35")
        fig.tight_layout(rect=(0, 0.03 + 0.02 * stamp.count("\n"), 1, 1))
    else:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def render(name, results=RESULTS):
    import results_pages
    spec, folder, page = results_pages.PAGES[name]
    folder, page = results / folder, results / page
    text = fill((folder / "page.md").read_text(), spec(folder), folder / "page.md")
    page.write_text(text)
    print(f"wrote {page}")


def main(argv):
    import results_pages
    results = RESULTS
    if argv[:1] == ["--results"] and len(argv) > 1:
        results, argv = Path(argv[1]), argv[2:]
    unknown = [n for n in argv if n not in results_pages.PAGES]
    if unknown:
        sys.exit(f"render_results.py: no page {', '.join(unknown)} (pages: {', '.join(results_pages.PAGES)})")
    for name in argv or results_pages.PAGES:
        render(name, results)


if __name__ == "__main__":
    main(sys.argv[1:])
