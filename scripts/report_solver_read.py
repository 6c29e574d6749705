#!/usr/bin/python3
"""Writes results/solver-read/README.md from results/solver-read/runs.json,
the measurement scripts/bench_read_vtu.sh leaves there: the read seconds of
each piece encoding, with the command, machine, commit and date.

    scripts/report_solver_read.py [results/solver-read]

Python standard library.
"""
import json
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import table  # noqa: E402

TARGET_S = 0.2  # for the raw piece


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "results/solver-read")
    data = json.loads((folder / "runs.json").read_text())
    rows, raw_median = [], None
    for piece in data["pieces"]:
        median = statistics.median(piece["seconds"])
        if piece["variant"] == "raw":
            raw_median = median
        rows.append([piece["label"], f"{piece['bytes']:,}", f"{median:.3f}",
                     ", ".join(f"{t:.3f}" for t in piece["seconds"])])
    verdict = ("" if raw_median is None else
               f" The raw piece's median, {raw_median:.3f} s, "
               + ("meets it." if raw_median <= TARGET_S else "**misses it**."))
    lines = ["# Reading a solver's piece", "",
             f"A 10⁶-node piece ({data['lattice']}³ lattice nodes, {data['tetrahedra'] / 1e6:.1f} M tetrahedra) as "
             "ParaView writes large pieces — appended raw binary, UInt64 headers, Int64 connectivity and offsets, "
             "Float64 points and field — read by `tetiso extract --mesh piece.vtu --array distance` into one domain: "
             "the report's `seconds.read` (file to domain: parsing, every check, the orientation of every "
             f"tetrahedron), one thread, {data['repeats']} runs each. Target: ≤ {TARGET_S} s for the raw piece."
             + verdict, "",
             table(["piece", "bytes", "median s", "each run, s"], rows), "",
             "The raw piece is mapped rather than read, its arrays converted straight from the mapping and its "
             "Int64 connectivity written into 32-bit indices in one pass; a compressed piece is bound by zlib's "
             "inflate.", "",
             "## Command, machine, commit, date", "",
             f"- Command: `{data['command']}`; page: `scripts/report_solver_read.py` from runs.json",
             f"- Commit: `{data['commit']}`",
             f"- Machine: {data['machine']}, load average before the run {data['load_before']}",
             f"- Date: {data['date']}", ""]
    (folder / "README.md").write_text("\n".join(lines))
    print(f"wrote {folder / 'README.md'}")


if __name__ == "__main__":
    main()
