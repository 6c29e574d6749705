"""job_gaps.py REPORT.json: one line of a tetiso run report: its total, the
last domain task's end, the domain tasks on GPUs, the gaps between a GPU's
grants (its domain records lie end to end within a grant) and the CPU
workers' median gap between two tasks."""
import collections
import json
import statistics
import sys

report = json.load(open(sys.argv[1]))
tasks = report["tasks"]
domains = [t for t in tasks if t["kind"] == "domain"]
on_gpu = sorted((t for t in domains if t["device"] != "cpu"), key=lambda t: t["start"])
gaps = [b["start"] - a["end"] for a, b in zip(on_gpu, on_gpu[1:]) if b["start"] - a["end"] > 1e-6]
by_rank = collections.defaultdict(list)
for t in tasks:
    if t["device"] == "cpu":
        by_rank[t["rank"]].append(t)
cpu_gaps = []
for ran in by_rank.values():
    ran.sort(key=lambda t: t["start"])
    cpu_gaps += [b["start"] - a["end"] for a, b in zip(ran, ran[1:])]
print("total %.2f last domain %.2f gpu domains %d grant gaps %.2f s (%d) cpu median gap %.4f"
      % (report["seconds"]["total"], max(t["end"] for t in domains), len(on_gpu), sum(gaps), len(gaps),
         statistics.median(cpu_gaps)))
