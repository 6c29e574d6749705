#!/usr/bin/python3
"""Writes results/extract-gpu/README.md: marching tetrahedra on the GPU
(core/src/extract_gpu.cu) against tetiso's CPU extraction on the same
machine, from bench/bench_extract.cpp's Google Benchmark output, with the
correctness runs of the same build.

    scripts/report_extract_gpu.py [results/extract-gpu]

Reads the folder's meta.json (command, machine, commit, date),
device/bench_extract.json and the test logs under device/. Python standard
library.
"""
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import load_aggregates, load_meta, provenance_section, table  # noqa: E402

PATTERN = r"(extract|domain)/([\w-]+)/N:(\d+)/threads:(\d+)/real_time"


def cell(case, stages=False):
    text = f"{case['time_ms']:,.1f} ({case['min_ms']:,.1f})"
    if stages:
        row = case["median"]
        text += " = " + " / ".join(f"{row[k] * 1e3:.2f}" for k in ("upload_s", "compute_s", "download_s"))
    return text


def test_summary(log):
    text = log.read_text()
    for pattern in (r"\d+% tests passed.*out of \d+", r"\d+ passed, \d+ failed", r"\[  PASSED  \] \d+ tests?"):
        found = re.findall(pattern, text)
        if found:
            return found[-1].replace("[  PASSED  ]", "passed:")
    return "no summary line"


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "results/extract-gpu")
    meta = load_meta(folder)
    context, cases = load_aggregates(folder / "device/bench_extract.json", PATTERN,
                                     lambda m: (m.group(1), m.group(2), int(m.group(3)), int(m.group(4))))
    sizes = sorted({key[2] for key in cases})
    threads = max(key[3] for key in cases)
    rows, whole = [], []
    for n in sizes:
        c = lambda *k: cases[k]  # noqa: E731
        rows.append([n, f"{c('extract', 'tetiso', n, 1)['median']['tets']:,.0f}",
                     f"{c('extract', 'tetiso', n, 1)['median']['triangles']:,.0f}",
                     cell(c("extract", "tetiso", n, 1)), cell(c("extract", "tetiso", n, threads)),
                     cell(c("extract", "gpu", n, 1), True), "**" + cell(c("extract", "gpu-lattice", n, 1), True) + "**"])
        whole.append([n, cell(c("domain", "tetiso", n, 1)), cell(c("domain", "gpu", n, 1))])
    first = sizes[0]
    lattice, one, all_cores = (cases[("extract", k, first, t)]["time_ms"]
                               for k, t in (("gpu-lattice", 1), ("tetiso", 1), ("tetiso", threads)))
    lines = ["# GPU extraction against the CPU's", "",
             f"Marching tetrahedra on one GPU ({context.get('gpu', '?')}) against tetiso's CPU extraction on the "
             f"same machine's {context.get('num_cpus', '?')}-core host. The problem is bench/bench_extract.cpp's: "
             "the paper field at level 0.5 on the N×N×N lattice as one domain (N = 100 is the mission's "
             "10⁶-node domain). Each GPU surface is the CPU's bit for bit (the tests below check it).", "",
             "Medians of 10 interleaved repetitions in milliseconds, fastest repetition in brackets. \"GPU, "
             "domain uploaded\" sends the whole domain (positions, values, ids, masks, 16-byte tetrahedra) and "
             "takes the piece back; \"GPU, lattice\" sends only the field values and builds nodes and tetrahedra "
             "on the device. After the = come the upload / compute / download milliseconds of the median repetition.", "",
             table(["N", "tetrahedra", "triangles", "CPU, 1 thread", f"CPU, {threads} threads",
                    "GPU, domain uploaded", "GPU, lattice"], rows), "",
             f"At N = {first} the GPU's lattice path is **{one / lattice:.1f}×** one core and "
             f"**{all_cores / lattice:.1f}×** all {threads} (medians of the same run).", "",
             "A domain from nothing to its piece (a job's domain task before reduction): building the domain "
             "and extracting it on one CPU thread against evaluating the field and the GPU's lattice path:", "",
             table(["N", "CPU, 1 thread", "GPU, lattice"], whole), "",
             "## Correctness runs on the same build", ""]
    for log in sorted((folder / "device").glob("*.log")):
        lines.append(f"- `device/{log.name}`: {test_summary(log)}")
    lines += [""] + provenance_section(meta, "scripts/report_extract_gpu.py results/extract-gpu")
    (folder / "README.md").write_text("\n".join(lines))
    print(f"wrote {folder / 'README.md'}")


if __name__ == "__main__":
    main()
