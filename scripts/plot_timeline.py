#!/usr/bin/env python3
"""Draws the timeline of a `tetiso run --report` file: one row per rank, one
bar per task. Each bar is split into its task's stages from the report's
stage_seconds: a domain's generation, extraction and reduction; a seam's
merge, region, reduction and splice, in colours of their own (reports
without stages, or with a seam's single "seam" stage, give one bar per task
or per seam). The legend gives each stage's total seconds over all tasks. A task that ran with more
than one thread (cores lent by idle workers) is labelled with the most it
had, e.g. "x4". A strip along the bottom of each bar gives the device the
task ran on (the report's "device": the CPU, or a GPU of the rank's node),
each device in a colour of its own, with its task count and seconds in the
legend; a task that waited for its device's grant is preceded by a thin
line of that length.

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
    # A task's stages run back to back from its start; what is left of its
    # span (receiving and unpacking its input, packing its result) stays
    # blank.
    # (kind, stage) in the order they run; a seam's reduction is not a
    # domain's, so it gets its own colour and legend entry.
    stage_order = {
        "domain": [("generate", "generate", "tab:green"), ("extract", "extract", "tab:olive"),
                   ("reduce", "reduce", "tab:blue"), ("domain", "domain", "tab:blue")],
        "seam": [("merge", "seam merge", "tab:orange"), ("region", "seam region", "tab:brown"),
                 ("reduce", "seam reduce", "tab:red"), ("splice", "seam splice", "tab:pink"),
                 ("seam", "seam", "tab:orange")],
    }
    colours = {}
    totals = {}

    fig, ax = plt.subplots(figsize=(10, 1.0 + 0.35 * len(ranks)))
    for t in tasks:
        y = row[t["rank"]]
        ax.barh(y, t["end"] - t["start"], left=t["start"], height=0.8, color="white", edgecolor="black",
                linewidth=0.2)
        stages = t.get("stage_seconds") or {t["kind"]: t["end"] - t["start"]}
        at = t["start"]
        for stage, label, colour in stage_order[t["kind"]]:
            if stage not in stages:
                continue
            width = min(stages[stage], t["end"] - at)
            ax.barh(y, width, left=at, height=0.8, color=colour, linewidth=0)
            colours[label] = colour
            totals[label] = totals.get(label, 0.0) + stages[stage]
            at += width
    # Where each task ran: the CPU in grey, the GPUs in colours the stages
    # do not use.
    device_palette = ["tab:purple", "tab:cyan", "gold", "black", "lime", "navy", "magenta", "teal"]
    devices = sorted({t.get("device", "cpu") for t in tasks}, key=lambda d: (d != "cpu", d))
    device_colour = {d: ("tab:gray" if d == "cpu" else device_palette[i % len(device_palette)])
                     for i, d in enumerate(x for x in devices if x != "cpu")}
    device_colour.setdefault("cpu", "tab:gray")
    device_totals = {}
    for t in tasks:
        device = t.get("device", "cpu")
        y = row[t["rank"]]
        ax.barh(y - 0.34, t["end"] - t["start"], left=t["start"], height=0.12, color=device_colour[device], linewidth=0)
        if t.get("wait_seconds", 0) > 0:
            ax.plot([t["start"] - t["wait_seconds"], t["start"]], [y - 0.34, y - 0.34], color=device_colour[device],
                    linewidth=0.6)
        count, seconds = device_totals.get(device, (0, 0.0))
        device_totals[device] = (count + 1, seconds + t["end"] - t["start"])
    for label, total in totals.items():
        ax.barh(-10, 0, color=colours[label], label=f"{label} ({total:.1f} s in all)")
    for device in devices:
        count, seconds = device_totals[device]
        ax.barh(-10, 0, color=device_colour[device], label=f"on {device}: {count} tasks, {seconds:.1f} s")
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
