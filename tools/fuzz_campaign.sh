#!/usr/bin/env bash
# A fuzzing campaign of the readers, recorded: tools/fuzz.sh with N inputs
# per reader (default 10^6; all readers, or those named), then one
# results/fuzz/READER.json per reader run (inputs, rate, coverage, corpus,
# findings, and the command, commit, date, machine and compiler), and
# results/fuzz/README.md rewritten by tools/render_results.py fuzz from every
# READER.json there, so a campaign over some readers keeps the others' rows.
#
#   tools/fuzz_campaign.sh [N] [READER...]
set -uo pipefail
cd "$(dirname "$0")/.." || exit 1
runs=${1:-1000000}
shift || true
started=$(date -u +%Y-%m-%dT%H:%MZ)
commit=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- core validation || echo "+changes")
start=$(date +%s)
tools/fuzz.sh --runs "$runs" "$@"
status=$?
seconds=$(($(date +%s) - start))

mkdir -p results/fuzz
# shellcheck source=/dev/null
machine="$(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), $(. /etc/os-release && echo "$PRETTY_NAME")"
for log in build-fuzz/logs/*.log; do
    reader=$(basename "$log" .log)
    [ $# -eq 0 ] || [[ " $* " == *" $reader "* ]] || continue
    # A log this campaign did not write (fuzz.sh stopped before the reader)
    # is an earlier run's, not this one's.
    [ "$(stat -c %Y "$log")" -ge "$start" ] || continue
    python3 - "$log" "$reader" "$runs $*" "$commit" "$started" "$seconds" "$machine" "clang $(clang++ -dumpversion)" \
        "$(find build-fuzz/corpus/"$reader" -type f | wc -l)" <<'PY' >"results/fuzz/$reader.json"
import json, re, sys
log, reader, arguments, commit, started, seconds, machine, compiler, corpus = sys.argv[1:]
runs = arguments.split()[0]
text = open(log, errors="replace").read()
last = lambda pattern: (re.findall(pattern, text) or [None])[-1]
finding = re.search(r"(ERROR: |runtime error|uncaught|deadly signal).{0,110}", text)
print(json.dumps({
    "reader": reader, "inputs": int(last(r"stat::number_of_executed_units: *(\d+)") or 0),
    "exec_per_s": int(last(r"stat::average_exec_per_sec: *(\d+)") or 0),
    "coverage_edges": int(last(r"cov: (\d+)") or 0), "features": int(last(r"ft: (\d+)") or 0),
    "corpus_entries": int(corpus), "finding": finding.group(0) if finding else None,
    "command": f"tools/fuzz_campaign.sh {arguments.strip()} (tools/fuzz.sh --runs {runs})", "commit": commit,
    "started": started, "campaign_seconds": int(seconds), "machine": machine, "compiler": compiler,
    "build": "every target and tetiso_core with AddressSanitizer and UndefinedBehaviorSanitizer, -O1 -g"}, indent=1))
PY
done
/usr/bin/python3 tools/render_results.py fuzz
echo "written: results/fuzz/README.md"
exit "$status"
