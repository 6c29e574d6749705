#!/usr/bin/env bash
# A fuzzing campaign of every reader, recorded: scripts/fuzz.sh with N inputs
# per reader (default 10^6), then results/fuzz/README.md written from its
# logs (command, machine, commit, date; per reader the inputs run, coverage,
# corpus, findings and seconds).
#
#   scripts/fuzz_campaign.sh [N] [READER...]
set -uo pipefail
cd "$(dirname "$0")/.."
runs=${1:-1000000}
shift || true
started=$(date -u +%Y-%m-%dT%H:%MZ)
commit=$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- core validation || echo "+changes")
start=$(date +%s)
scripts/fuzz.sh --runs "$runs" "$@" | tee build-fuzz-summary.txt
status=${PIPESTATUS[0]}
seconds=$(($(date +%s) - start))

mkdir -p results/fuzz
{
    echo "# Fuzzing campaign of the readers"
    echo
    echo "Written by \`scripts/fuzz_campaign.sh $runs${*:+ $*}\` (which runs \`scripts/fuzz.sh --runs $runs\`):"
    echo "libFuzzer, clang $(clang++ -dumpversion), every target and tetiso_core built with AddressSanitizer and"
    echo "UndefinedBehaviorSanitizer (-O1 -g), each reader from its seeds in validation/fuzz/corpus/ after replaying"
    echo "validation/fuzz/regressions/. A finding is a crash, a hang over 10 s, a sanitizer report, more than 2 GB of"
    echo "memory, or an exception other than tetiso::Error."
    echo
    echo "- commit: $commit; started $started; $seconds s in all"
    echo "- machine: $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), $(. /etc/os-release && echo "$PRETTY_NAME"), shared with other builds, run under nice"
    echo "- exit status of fuzz.sh: $status ($([ "$status" -eq 0 ] && echo "no finding" || echo "findings: see below"))"
    echo
    echo "| reader | inputs run | exec/s | coverage (edges) | features | corpus entries | findings |"
    echo "|---|---:|---:|---:|---:|---:|---|"
    for log in build-fuzz/logs/*.log; do
        reader=$(basename "$log" .log)
        [ $# -eq 0 ] || [[ " $* " == *" $reader "* ]] || continue
        inputs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
        rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
        cov=$(grep -oE 'cov: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)
        ft=$(grep -oE 'ft: [0-9]+' "$log" | tail -1 | cut -d' ' -f2)
        corpus=$(ls build-fuzz/corpus/"$reader" | wc -l)
        finding=$(grep -m1 -E 'ERROR: |runtime error|uncaught|deadly signal' "$log" | cut -c1-120 || true)
        echo "| $reader | ${inputs:-?} | ${rate:-?} | ${cov:-?} | ${ft:-?} | $corpus | ${finding:-none} |"
    done
    echo
    echo "Findings of earlier runs are kept as inputs in validation/fuzz/regressions/READER/ (replayed by every"
    echo "fuzz.sh run) and as tests of the suite: fuzz_split's first, a merge tree whose children's counts"
    echo "overflow an int when summed, is MeshSplit.DamagedOrMismatchedFilesAreClearErrors."
} >results/fuzz/README.md
rm -f build-fuzz-summary.txt
echo "written: results/fuzz/README.md"
exit "$status"
