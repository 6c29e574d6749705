#!/usr/bin/env python3
"""Writes results/fuzz/README.md from the READER.json files that
scripts/fuzz_campaign.sh leaves there, one row per reader with the command,
commit, date and machine of the campaign that ran it.

    scripts/report_fuzz.py [results/fuzz]

Python standard library.
"""
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import table  # noqa: E402


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "results/fuzz")
    readers = [json.loads(p.read_text()) for p in sorted(folder.glob("*.json"))]
    campaigns = {}
    for r in readers:
        campaigns.setdefault((r["command"], r["commit"], r["started"], r["machine"], r["compiler"], r["build"]),
                             []).append(r["reader"])
    labels = {key: chr(ord("A") + i) for i, key in enumerate(campaigns)}
    rows = []
    for r in readers:
        key = next(k for k, names in campaigns.items() if r["reader"] in names)
        rows.append([r["reader"], f"{r['inputs']:,}", f"{r['exec_per_s']:,}", f"{r['coverage_edges']:,}",
                     f"{r['features']:,}" if r.get("features") else "not recorded", f"{r['corpus_entries']:,}",
                     r["finding"] or "none", labels[key]])
    clean = all(r["finding"] is None for r in readers)
    lines = ["# Fuzzing the readers", "",
             "libFuzzer over every reader of tetiso's inputs (validation/fuzz/fuzz_*.cpp), each from its seeds in "
             "validation/fuzz/corpus/ and what earlier runs on the machine added, after replaying "
             "validation/fuzz/regressions/. A finding is a crash, a hang "
             "over 10 s, a sanitizer report, more than 2 GB of memory, or an exception other than tetiso::Error. "
             + ("**No reader has a finding.**" if clean else "**Some readers have findings: see the table.**"), "",
             table(["reader", "inputs run", "exec/s", "coverage (edges)", "features", "corpus entries", "findings",
                    "campaign"], rows), "",
             "Findings of earlier runs are kept as inputs in validation/fuzz/regressions/READER/ (replayed by every "
             "scripts/fuzz.sh run) and as tests of the suite.", "", "## Command, machine, commit, date", ""]
    for (command, commit, started, machine, compiler, build), names in campaigns.items():
        lines.append(f"- Campaign {labels[(command, commit, started, machine, compiler, build)]} "
                     f"({', '.join(names)}): `{command}`; commit {commit}; started {started}; {machine}; "
                     f"{compiler}, {build}")
    lines += ["", "`scripts/fuzz_campaign.sh [N] [READER...]` runs a campaign and rewrites this page; "
              "`scripts/report_fuzz.py results/fuzz` rewrites it from the READER.json files alone.", ""]
    (folder / "README.md").write_text("\n".join(lines))
    print(f"wrote {folder / 'README.md'}")


if __name__ == "__main__":
    main()
