#!/usr/bin/python3
"""Writes results/scale/README.md: `tetiso run` at the mission's scale (the
paper's problem at N = 1000, 10^9 nodes, 1000 domains, 15 workers), beside
the paper's N = 500 job, with `tetiso check` of each surface, the workers'
peak memory, the fields of known topology at the same scale, and the job's
timeline (timeline.png, drawn by scripts/plot_timeline.py).

    scripts/report_scale.py [results/scale]

Reads the folder's meta.json (command, machine, commit and date of each set
of files) and the `tetiso run --report` and `tetiso check` JSON it names.
Dependencies: python3; python3-matplotlib for the timeline.
"""
import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_report_common import load_meta, provenance_section, table, topology_summary  # noqa: E402


def load(folder, name):
    return json.loads((folder / name).read_text())


def busy(report):
    tasks = sum(t["end"] - t["start"] for t in report["tasks"])
    return tasks, tasks / (report["workers"] * report["seconds"]["job"])


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "results/scale")
    meta = load_meta(folder)
    lines = ["# `tetiso run` at the mission's scale: 10⁹ nodes, 1000 domains", "",
             "The paper's test problem (field 2cos(10x)+2sin(10y)+cos(10z) at 0.5 on the N×N×N lattice over "
             "[0,5]³) at N = 1000: 10⁹ nodes and 5.98·10⁹ tetrahedra, split by recursive coordinate bisection "
             "into 1000 domains of about 10⁶ nodes (the domain size of the paper's 125-domain series), run by 15 "
             "workers on a 16-core node, beside the paper's own N = 500 job with 125 domains. The mission names "
             "meshes of 10⁸–10⁹ nodes in about 1000 domains.", "", "## Result", ""]
    rows = []
    for name, label in (("n1000-d1000", "N = 1000, 1000 domains"), ("n500-d125", "N = 500, 125 domains")):
        r, c = load(folder, f"{name}.json"), load(folder, f"{name}-check.json")
        tasks, share = busy(r)
        angles = c["topology"]["min_angle_deg"]
        rows.append([label, f"**{r['seconds']['job']:.2f}**", f"{tasks:.1f}", f"{share:.0%}",
                     f"{r['raw_triangles']:,} → {r['triangles']:,} ({r['raw_triangles'] / r['triangles']:.0f}×)",
                     f"{r['raw_triangles'] / r['seconds']['job'] / 1e6:.2f} M",
                     f"{angles['below_1']:,} ({angles['below_1'] / angles['triangles']:.3%})",
                     topology_summary(c)])
    lines += [table(["run", "job s", "tasks' sum s", "workers busy", "raw → reduced triangles",
                     "raw triangles per s", "angles below 1°", "`tetiso check`"], rows), "",
              "*Job* is the report's `seconds.job`: every task, domain generation included, from the first task "
              "handed out to the root seam's piece arriving on rank 0. *Workers busy* is the tasks' sum over "
              "15 × job. One run each; the machine is lent and its speed varies between calls, so times "
              "compare within one call only.", ""]
    big, small = load(folder, "n1000-d1000.json"), load(folder, "n500-d125.json")
    lines += [f"N = 1000 holds {big['raw_triangles'] / small['raw_triangles']:.2f}× N = 500's raw triangles and "
              f"took {big['seconds']['job'] / small['seconds']['job']:.2f}× its job time. Both reduced surfaces "
              "have the same per-component signature: the isosurface of the same field at twice the "
              "resolution.", ""]
    mem = load(folder, "memory-n1000-d1000.json")
    peaks = [k / 1024 for k in mem["peak_rss_kib"]]
    domain_mib = mem["tets"] / mem["domains"] * 16 / 2**20
    lines += ["## Memory", "",
              f"Peak resident memory per rank of the same N = 1000 job (`scripts/rank_peak_rss.py`, an earlier "
              f"commit, {mem['triangles']:,} triangles): rank 0, which holds the pieces, {peaks[0]:.1f} MiB; the "
              f"worst worker {max(peaks[1:]):.1f} MiB, {max(peaks[1:]) / domain_mib:.1f}× one domain's "
              f"tetrahedra ({domain_mib:.0f} MiB at 16 bytes each).", ""]
    rows = []
    for field, expected in (("sphere", "genus 0, closed"), ("torus", "genus 1, closed"),
                            ("gyroid", "no closed form at this lattice (the gyroid is cut by the cube)")):
        r, c = load(folder, f"fields-{field}.json"), load(folder, f"fields-{field}-check.json")
        tasks, share = busy(r)
        rows.append([field, f"{r['seconds']['job']:.2f}", f"{r['raw_triangles']:,} → {r['triangles']:,} "
                     f"({r['raw_triangles'] / r['triangles']:.0f}×)", f"{share:.0%}", topology_summary(c), expected])
    lines += ["## Fields of known topology at the same scale", "",
              table(["field", "job s", "raw → reduced triangles", "workers busy", "`tetiso check`", "expected"],
                    rows), ""]
    timeline = folder / "timeline.png"
    done = subprocess.run([sys.executable, str(Path(__file__).resolve().parent / "plot_timeline.py"),
                           str(folder / "n1000-d1000.json"), "-o", str(timeline)], check=False).returncode == 0
    if done:
        lines += ["## Timeline", "", "One row per rank, one bar per task split into its stages "
                  "(`scripts/plot_timeline.py n1000-d1000.json`):", "", "![timeline of the N = 1000 job](timeline.png)", ""]
    lines += provenance_section(meta, "scripts/report_scale.py results/scale")
    (folder / "README.md").write_text("\n".join(lines))
    print(f"wrote {folder / 'README.md'}")


if __name__ == "__main__":
    main()
