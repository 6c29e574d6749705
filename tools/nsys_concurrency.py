#!/usr/bin/env python3
"""How busy the GPU and each stream were in an nsys trace (its .sqlite export).

Usage: nsys_concurrency.py TRACE.sqlite [START_FRACTION]

Over the part of the run after START_FRACTION of its device timeline (0.5
unless told: for bench_gpu_streams, about its warm pass), prints: the
share of the window with at least one kernel or copy on the device, the
mean number of kernels running while any is, the kernels' count, rate and
durations, each stream's busy share (a stream idle while the device is
not is waiting for its host thread), and the host time in the CUDA calls
that took most of it. Standard library only: the device machines have
nothing else.
"""
import sqlite3
import statistics
import sys


def union_length(intervals):
    total, end = 0, None
    for s, e in sorted(intervals):
        if end is None or s > end:
            total += e - s
            end = e
        elif e > end:
            total += e - end
            end = e
    return total


def clip(intervals, lo, hi):
    return [(max(s, lo), min(e, hi)) for s, e in intervals if e > lo and s < hi]


def tables(db):
    return {r[0] for r in db.execute("select name from sqlite_master where type='table'")}


def main():
    db = sqlite3.connect(sys.argv[1])
    start_fraction = float(sys.argv[2]) if len(sys.argv) > 2 else 0.5
    have = tables(db)
    kernels = db.execute("select start, end, streamId from CUPTI_ACTIVITY_KIND_KERNEL").fetchall()
    copies = []
    if "CUPTI_ACTIVITY_KIND_MEMCPY" in have:
        copies += db.execute("select start, end, streamId from CUPTI_ACTIVITY_KIND_MEMCPY").fetchall()
    if "CUPTI_ACTIVITY_KIND_MEMSET" in have:
        copies += db.execute("select start, end, streamId from CUPTI_ACTIVITY_KIND_MEMSET").fetchall()
    first = min(s for s, _, _ in kernels)
    last = max(e for _, e, _ in kernels)
    lo = first + (last - first) * start_fraction
    window = last - lo
    k = clip([(s, e) for s, e, _ in kernels], lo, last)
    work = k + clip([(s, e) for s, e, _ in copies], lo, last)
    busy = union_length(work)
    kernel_union = union_length(k)
    durations = sorted(e - s for s, e in k)
    print(f"window: the last {100 * (1 - start_fraction):.0f}% of the device timeline, {window / 1e9:.3f} s")
    print(f"device busy (a kernel or copy running): {100 * busy / window:.1f}% of the window")
    print(f"kernels running while any is: {sum(durations) / max(kernel_union, 1):.2f} on average")
    print(f"kernels: {len(durations)}, {len(durations) / (window / 1e9):.0f} per second; duration median "
          f"{statistics.median(durations) / 1e3:.1f} us, 90th percentile {durations[int(0.9 * len(durations))] / 1e3:.1f} us, "
          f"mean {statistics.mean(durations) / 1e3:.1f} us")
    streams = {}
    for s, e, stream in kernels + copies:
        streams.setdefault(stream, []).append((s, e))
    shares = []
    for stream, intervals in sorted(streams.items()):
        inside = clip(intervals, lo, last)
        if not inside:
            continue
        shares.append(union_length(inside) / window)
    if shares:
        print(f"streams with work in the window: {len(shares)}; each busy {100 * min(shares):.1f}% to "
              f"{100 * max(shares):.1f}% of it (mean {100 * statistics.mean(shares):.1f}%)")
    if "CUPTI_ACTIVITY_KIND_RUNTIME" in have and "StringIds" in have:
        rows = db.execute(
            "select s.value, count(*), sum(r.end - r.start) from CUPTI_ACTIVITY_KIND_RUNTIME r "
            "join StringIds s on r.nameId = s.id where r.start >= ? group by s.value order by 3 desc limit 8",
            (lo,)).fetchall()
        print("host time in CUDA calls over the window (all threads together):")
        for name, count, total in rows:
            print(f"  {total / 1e9:8.3f} s  {count:8d} calls  {total / count / 1e3:8.1f} us each  {name}")
    if "GPU_METRICS" in have and "TARGET_INFO_GPU_METRICS" in have:
        names = dict(db.execute("select distinct metricId, metricName from TARGET_INFO_GPU_METRICS").fetchall())
        rows = db.execute("select metricId, avg(value) from GPU_METRICS where timestamp >= ? and timestamp <= ? "
                          "group by metricId", (lo, last)).fetchall()
        print("GPU metrics sampled over the window (mean):")
        for metric, value in rows:
            print(f"  {value:8.2f}  {names.get(metric, metric)}")


if __name__ == "__main__":
    main()
