#!/usr/bin/env python3
"""Runs a command, waits for it, and appends one JSON line with its MPI rank
and peak resident memory (the kernel's ru_maxrss of that one child, in KiB)
to the file named by $TETISO_RSS_LOG. Exits with the command's status.

    TETISO_RSS_LOG=rss.jsonl mpirun -np 16 tools/rank_peak_rss.py build/core/tetiso run ...

A wrapper rather than /usr/bin/time because GNU time is not installed
everywhere (the device machines lack it) and its output would interleave with
the job's on stderr; the command inherits the launcher's environment, so MPI
initialises in it as it would without the wrapper.
"""
import json
import os
import signal
import subprocess
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    child = subprocess.Popen(sys.argv[1:])
    # mpirun stops a job by signalling the processes it started: pass the
    # signal on so the job's own process does not outlive its launcher.
    for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, lambda s, _frame: child.send_signal(s))
    while True:
        try:
            _, status, usage = os.wait4(child.pid, 0)
            break
        except InterruptedError:
            continue
    code = os.waitstatus_to_exitcode(status)
    log = os.environ.get("TETISO_RSS_LOG")
    if log:
        rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")))
        line = json.dumps({"rank": rank, "peak_rss_kib": usage.ru_maxrss, "user_s": usage.ru_utime,
                           "system_s": usage.ru_stime, "status": code}) + "\n"
        # One write of a short line to a file opened for appending: lines from
        # concurrent ranks do not interleave.
        fd = os.open(log, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, line.encode())
        finally:
            os.close(fd)
    sys.exit(code if code >= 0 else 128 - code)


if __name__ == "__main__":
    main()
