#!/usr/bin/env python3
"""Writes a benchmark run's meta.json (tools/bench_*.sh, tools/gpu_check.sh):

    tools/bench_meta.py OUT.json key=value...

OUT.json holds the given keys (the run's own facts: commands, source, commit,
load, environment) and the machine's: CPU model and counts, memory, kernel,
compiler, date. Python standard library only.
"""
import json
import os
import re
import subprocess
import sys
from datetime import datetime, timezone


def _run(command):
    try:
        return subprocess.run(command, capture_output=True, text=True, check=False).stdout
    except OSError:
        return ""


def _lscpu(field):
    match = re.search(rf"^{re.escape(field)}:\s*(.*)$", _run(["lscpu"]), re.MULTILINE)
    return match.group(1).strip() if match else "?"


def machine_facts():
    memory_kib = 0
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal:"):
                memory_kib = int(line.split()[1])
    uname = os.uname()
    compiler = _run(["c++", "--version"]).splitlines()
    return {
        "cpu_model": _lscpu("Model name"),
        "cpus": str(len(os.sched_getaffinity(0))),  # as nproc counts them
        "cores_per_socket": _lscpu("Core(s) per socket"),
        "threads_per_core": _lscpu("Thread(s) per core"),
        # As `free -g` prints it, which is what bench_extract.sh records.
        "memory": f"{memory_kib // 2**20} GiB",
        "kernel": f"{uname.sysname} {uname.release}",
        "compiler": compiler[0] if compiler else "?",
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    }


def main(argv):
    if len(argv) < 1 or any("=" not in arg for arg in argv[1:]):
        sys.exit("usage: tools/bench_meta.py OUT.json key=value...")
    meta = dict(arg.split("=", 1) for arg in argv[1:])
    meta.update(machine_facts())
    with open(argv[0], "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1:])
