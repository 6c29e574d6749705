#!/usr/bin/env bash
# Builds the libFuzzer targets (validation/fuzz/fuzz_*.cpp: one per reader,
# and `reduce`, which holds reduce() to its contract on any surface read)
# with clang, AddressSanitizer and UndefinedBehaviorSanitizer in build-fuzz/,
# and runs them: all, or the targets named.
#
#   tools/fuzz.sh [--seconds S | --runs N] [READER...]    READER: ply, vtp, tetgen, partition, split, reduce, ...
#
# Each target first replays its regressions (validation/fuzz/regressions/
# READER/, inputs that once failed), then fuzzes from its seeds
# (validation/fuzz/corpus/READER/) and what earlier runs added
# (build-fuzz/corpus/READER/), for S seconds (default 30) or N inputs. A
# crash, a hang (10 s), a sanitizer report or an exception other than
# tetiso::Error is written to build-fuzz/findings/READER/ and fails the run.
# Logs: build-fuzz/logs/READER.log; one summary line per reader on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."

limit=(-max_total_time=30)
readers=()
while [ $# -gt 0 ]; do
    case $1 in
    --seconds) limit=(-max_total_time="$2"); shift 2 ;;
    --runs) limit=(-runs="$2"); shift 2 ;;
    -h | --help) sed -n '2,14p' "$0"; exit 0 ;;
    *) readers+=("${1#fuzz_}"); shift ;;
    esac
done
if [ ${#readers[@]} -eq 0 ]; then
    for source in validation/fuzz/fuzz_*.cpp; do
        name=$(basename "$source" .cpp)
        readers+=("${name#fuzz_}")
    done
fi

if ! command -v clang++ >/dev/null; then
    echo "fuzz.sh: clang++ is needed (Debian: apt-get install clang)" >&2
    exit 2
fi
mkdir -p build-fuzz
cmake -S . -B build-fuzz -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DTETISO_FUZZ=ON -DTETISO_TESTS=OFF -DTETISO_BENCH=OFF \
    -DTETISO_REFERENCE=OFF -DTETISO_CUDA=OFF -DTETISO_MPI=OFF >build-fuzz/build.log 2>&1 ||
    { cat build-fuzz/build.log >&2; exit 2; }
targets=()
for reader in "${readers[@]}"; do targets+=("fuzz_$reader"); done
cmake --build build-fuzz -j "$(nproc)" --target "${targets[@]}" >>build-fuzz/build.log 2>&1 ||
    { tail -40 build-fuzz/build.log >&2; exit 2; }

failed=0
for reader in "${readers[@]}"; do
    binary=build-fuzz/validation/fuzz/fuzz_$reader
    corpus=build-fuzz/corpus/$reader findings=build-fuzz/findings/$reader log=build-fuzz/logs/$reader.log
    mkdir -p "$corpus" "$findings" build-fuzz/logs
    options=(-rss_limit_mb=2048 -timeout=10 -print_final_stats=1 -artifact_prefix="$findings/")
    status=0
    regressions=validation/fuzz/regressions/$reader
    if [ -d "$regressions" ] && [ -n "$(ls -A "$regressions")" ]; then
        "$binary" "${options[@]}" "$regressions"/* >"$log" 2>&1 || status=$?
    fi
    corpora=("$corpus")
    [ -d "validation/fuzz/corpus/$reader" ] && corpora+=("validation/fuzz/corpus/$reader")
    [ "$status" -ne 0 ] || "$binary" "${options[@]}" "${limit[@]}" "${corpora[@]}" >>"$log" 2>&1 || status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    coverage=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1)
    if [ "$status" -eq 0 ]; then
        echo "fuzz_$reader: ${runs:-0} inputs, ${coverage:-no coverage line}, no finding"
    else
        echo "fuzz_$reader: FINDING (status $status) after ${runs:-?} inputs: $(grep -m1 -E 'ERROR|runtime error|uncaught|deadly signal|timeout' "$log" || true)"
        echo "  log: $log; input: $(ls -t "$findings" | head -1)"
        failed=1
    fi
done
exit "$failed"
