#!/usr/bin/env python3
"""Draws the timeline of a `tetiso run --report` file: one row per rank, one
bar per task (domain tasks and seams in two colours); a task that ran with
more than one thread (cores lent by idle workers) is labelled with the most
it had, e.g. "x4".

    scripts/plot_timeline.py report.json -o timeline.png
"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("report")
    parser.add_argument("-o", "--output", required=True)
    args = parser.parse_args()
    report = json.load(open(args.report))
    tasks = report["tasks"]
    ranks = sorted({t["rank"] for t in tasks})
    row = {rank: i for i, rank in enumerate(ranks)}
    colours = {"domain": "tab:blue", "seam": "tab:orange"}

    fig, ax = plt.subplots(figsize=(10, 1.0 + 0.35 * len(ranks)))
    for kind in ("domain", "seam"):
        bars = [(t["start"], t["end"] - t["start"], row[t["rank"]]) for t in tasks if t["kind"] == kind]
        for start, width, y in bars:
            ax.barh(y, width, left=start, height=0.8, color=colours[kind], edgecolor="black", linewidth=0.2)
        ax.barh(-10, 0, color=colours[kind], label=f"{kind} ({len(bars)})")
    for t in tasks:
        if t.get("threads", 1) > 1 and t["kind"] == "domain":
            ax.text(t["end"], row[t["rank"]], f" x{t['threads']}", va="center", ha="left", fontsize=7)
    ax.set_ylim(-0.6, len(ranks) - 0.4)
    ax.set_yticks(range(len(ranks)), [f"rank {r}" for r in ranks])
    ax.set_xlabel("seconds since the job started")
    ax.set_title(
        f"tetiso run: N={report['lattice']}, D={report['domains']}, {report['workers']} workers, "
        f"{report['seconds']['job']:.2f} s, {report['raw_triangles']:,} -> {report['triangles']:,} triangles"
    )
    ax.legend(loc="lower left")  # rank 0 works only at the end: its row starts empty
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)


if __name__ == "__main__":
    main()
