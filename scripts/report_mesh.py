#!/usr/bin/python3
"""Writes results/mesh/README.md: `tetiso run` over an unstructured TetGen
mesh of the paper's cube split into domains by METIS, held whole on every
rank (`run --mesh`) against the same partition written as one file per
domain (`tetiso split`, then `run --split`): wall and job time, each rank's
peak memory, and whether the two surfaces are the same bytes.

    scripts/report_mesh.py [results/mesh]

Reads the folder's meta.json (command, machine, commit, date), the two
reports (mesh.json, split.json), the per-rank peaks (rss-MODE.jsonl, from
scripts/rank_peak_rss.py) and scripts/split_job.sh's log (the split's
seconds, the wall times, the cmp of the surfaces). Python standard library.
"""
import json
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import load_meta, provenance_section, table  # noqa: E402


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "results/mesh")
    meta = load_meta(folder)
    log = (folder / "split_job.log").read_text()
    split_seconds, same = re.search(r"tetiso split: ([\d.]+) s; same surface: (\w+)", log).groups()
    rows, reports, peaks = [], {}, {}
    for mode, job in (("mesh", "`run --mesh cube.1 --domains {}`"), ("split", "`run --split DIR`")):
        r = reports[mode] = json.loads((folder / f"{mode}.json").read_text())
        wall = float(re.search(rf"run --{mode}: .*wall ([\d.]+) s", log).group(1))
        ranks = {}
        for line in (folder / f"rss-{mode}.jsonl").read_text().splitlines():
            record = json.loads(line)
            ranks[record["rank"]] = record["peak_rss_kib"] / 1024
        peaks[mode] = ranks
        workers = [v for k, v in ranks.items() if k != 0]
        rows.append([job.format(r["domains"]), f"{wall:.2f}", f"{r['seconds']['job']:.2f}",
                     f"{min(workers):,.1f}–{max(workers):,.1f}", f"{ranks[0]:,.1f}",
                     f"{sum(ranks.values()) / 1024:.2f}", f"{r['triangles']:,}"])
    m = reports["mesh"]
    lines = ["# The job over an unstructured mesh", "",
             f"`tetiso run` over a TetGen quality mesh of the paper's cube ({m['nodes']:,} nodes, {m['tets']:,} "
             f"tetrahedra, mean edge length {m['spacing']:.4f}), the paper field at {m['level']}, split by METIS "
             f"into {m['domains']} domains and run by {m['ranks']} MPI ranks ({m['workers']} workers). "
             "`run --mesh` has every rank read the whole mesh and partition it before the first task; "
             "`tetiso split` does that once and writes one file per domain, which `run --split` reads as its "
             "tasks need them.", "",
             table(["job", "wall s", "job s", "peak per worker MiB", "peak rank 0 MiB", "peaks summed GiB",
                    "triangles"], rows), "",
             f"- Same surface, byte for byte (`cmp`): {same}. Raw {m['raw_triangles']:,} → reduced "
             f"{m['triangles']:,} triangles (max error {m['max_error']:.4f}, 0.25 of the mean edge length).",
             f"- `tetiso split` itself took {float(split_seconds):.2f} s: reading the text files and METIS, "
             "which `run --mesh` repeats on every rank before the first task (the gap between its wall and job "
             "time).",
             "- *Job* is the report's `seconds.job` (first task handed out to the root seam's piece on rank 0); "
             "*wall* the whole `mpirun`. Peaks are each rank's `ru_maxrss` (`scripts/rank_peak_rss.py`).", ""]
    lines += provenance_section(meta, "scripts/report_mesh.py results/mesh")
    (folder / "README.md").write_text("\n".join(lines))
    print(f"wrote {folder / 'README.md'}")


if __name__ == "__main__":
    main()
