#!/usr/bin/python3
"""Takes a device machine's measurement outputs into a results folder, whole
(the new files replace the old measurement), then renders its page.

    tools/collect_results.py hardware OUT
        OUT: a `tools/gpu_check.sh jobs` folder; its reports (gzipped), cmp
        verdicts and meta.json go to results/hardware-comparison/.
    tools/collect_results.py paper INPUT...
        INPUT: an OUTDIR of tools/paper_reproduction.sh or files in it. Sweep
        outputs of tools/sweep_speedup.py (any name) are merged into
        sweep.json; stream.json (bench_stream), check-dD.json (`tetiso check`
        of D domains' surface) and *machine*.txt are copied, into
        results/paper-reproduction/. The pictures and render*.json that
        tools/render_surface.py writes there stay.
"""
import gzip
import json
import re
import shutil
import sys
from pathlib import Path

from render_results import RESULTS, render


def hardware(source):
    out = RESULTS / "hardware-comparison"
    page = (out / "page.md").read_text()
    shutil.rmtree(out)
    out.mkdir()
    (out / "page.md").write_text(page)
    shutil.copy(source / "meta.json", out / "meta.json")
    for report in source.glob("n*-d*-*.json"):
        (out / (report.name + ".gz")).write_bytes(gzip.compress(report.read_bytes(), mtime=0))
    for verdict in source.glob("n*-d*-cmp.txt"):
        shutil.copy(verdict, out / verdict.name)
    render("hardware-comparison")


def kind(path):
    data = json.loads(path.read_text())
    if "runs" in data:
        return "sweep", None
    if "kernel" in data and "results" in data:
        return "stream", None
    if "topology" in data:
        for text in (path.name, data.get("file", "")):
            match = re.search(r"-d(\d+)", text)
            if match:
                return "check", int(match[1])
        sys.exit(f"collect_results.py: {path}: cannot tell which series it checks")
    sys.exit(f"collect_results.py: {path}: not a sweep, stream or check output")


def paper(inputs):
    from sweep_speedup import merged, write
    out = RESULTS / "paper-reproduction"
    files = [f for item in map(Path, inputs) for f in (sorted(item.iterdir()) if item.is_dir() else [item])]
    for stale in [*out.glob("check-d*.json"), out / "stream.json", out / "machine.txt"]:
        stale.unlink(missing_ok=True)
    sweeps = []
    for path in files:
        if path.suffix == ".txt" and "machine" in path.name:
            shutil.copyfile(path, out / "machine.txt")
        elif path.suffix == ".json":
            what, domains = kind(path)
            if what == "sweep":
                sweeps.append(path)
            else:
                shutil.copyfile(path, out / (f"check-d{domains}.json" if what == "check" else "stream.json"))
    if not sweeps:
        sys.exit("collect_results.py: no sweep output among the inputs")
    meta, runs = merged(sweeps, " ".join(["tools/collect_results.py paper", *inputs]))
    write(str(out / "sweep"), meta, runs)
    (out / "sweep.csv").unlink(missing_ok=True)  # the page's tables say what the CSV did
    (out / "sweep.png").unlink(missing_ok=True)  # the page draws its own
    render("paper-reproduction")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "hardware":
        hardware(Path(sys.argv[2]))
    elif len(sys.argv) >= 3 and sys.argv[1] == "paper":
        paper(sys.argv[2:])
    else:
        sys.exit("usage: tools/collect_results.py hardware OUT | paper INPUT...")
