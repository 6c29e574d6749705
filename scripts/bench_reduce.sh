#!/usr/bin/env bash
# Builds the reduction benchmark (Release) and regenerates results/reduce/:
#   bench_reduce.json  Google Benchmark output: tetiso's reduce (1 and all
#                      threads) and meshoptimizer's meshopt_simplify to the
#                      same triangle count on the N=100 paper surface,
#                      aggregates of several repetitions, quality counters
#   meta.json          command, machine, commit
#   README.md          the report, by scripts/report_reduce.py
#
# Usage: scripts/bench_reduce.sh [--commit REV] [-- bench_reduce flags...]
#   --commit REV  measure the committed tree REV (exported with git archive
#                 into the build directory) instead of the working tree, so
#                 that the report names exactly what was measured even while
#                 others edit the checkout. Only the harness, bench/, is
#                 taken from the working tree where it differs from REV, and
#                 the report says so. Committed results use --commit HEAD.
# Environment: BUILD_DIR (default build-bench-reduce), JOBS (default 2),
#   REPETITIONS (default 10), SIZES (default 100), OMP_WAIT_POLICY (default
#   passive: see bench_extract.sh for why).
# Repetitions of all cases run interleaved in random order, so that other load
# on a shared machine falls on tetiso and meshoptimizer alike.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

commit_rev=""
bench_flags=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --commit) commit_rev=$2; shift 2 ;;
    --) shift; bench_flags=("$@"); break ;;
    *) echo "bench_reduce.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done

build=${BUILD_DIR:-$root/build-bench-reduce}
jobs=${JOBS:-2}
repetitions=${REPETITIONS:-10}
sizes=${SIZES:-100}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
out=$root/results/reduce

if [[ -n $commit_rev ]]; then
  commit=$(git rev-parse --verify "$commit_rev^{commit}")
  source_dir=$build/snapshot-${commit:0:12}
  build_dir=$build/snapshot-${commit:0:12}-build
  if [[ ! -d $source_dir ]]; then
    mkdir -p "$source_dir.tmp"
    git archive "$commit" | tar -x -C "$source_dir.tmp"
    mv "$source_dir.tmp" "$source_dir"
  fi
  source_state="committed tree $commit (exported with git archive)"
  # The harness may be newer than the code it measures (a benchmark written
  # while the code changes): bench/ is laid over the snapshot, never the
  # library. It is staged apart and swapped in only when it differs, touched so
  # that Ninja rebuilds it even when the new files are older than the objects.
  harness_changes=$( (git diff --name-only "$commit" -- bench; git ls-files --others --exclude-standard -- bench) |
    sort -u | paste -sd' ')
  staged=$source_dir.harness.tmp
  rm -rf "$staged"
  mkdir -p "$staged"
  if [[ -n $harness_changes ]]; then
    git ls-files --cached --others --exclude-standard -- bench | while read -r file; do
      if [[ -f $file ]]; then echo "$file"; fi
    done | tar -cf - -T - | tar -xf - -C "$staged"
    source_state+=", with the benchmark harness bench/ from the working tree, which differs from it in: $harness_changes"
  else
    git archive "$commit" bench | tar -x -C "$staged"
  fi
  if ! diff -rq "$staged/bench" "$source_dir/bench" >/dev/null 2>&1; then
    rm -rf "$source_dir/bench"
    mv "$staged/bench" "$source_dir/bench"
    find "$source_dir/bench" -type f -exec touch {} +
  fi
  rm -rf "$staged"
else
  commit=$(git rev-parse HEAD)
  source_dir=$root
  build_dir=$build
  # Only these paths go into the benchmark program.
  changed=$(git status --porcelain -- CMakeLists.txt core validation reference bench | awk '{print $2}' | paste -sd' ')
  source_state="working tree on $commit${changed:+, with uncommitted changes in: $changed}"
fi

cmake -S "$source_dir" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DTETISO_BENCH=ON -DTETISO_REFERENCE=ON -DTETISO_TESTS=OFF >/dev/null
# bench_reduce is not a target where Google Benchmark or meshoptimizer is missing.
cmake --build "$build_dir" -j "$jobs" --target bench_reduce ||
  { echo "bench_reduce.sh: bench_reduce was not built (are Google Benchmark and meshoptimizer installed?)" >&2; exit 1; }
bin=$build_dir/bench

mkdir -p "$out"
bench_cmd=("$bin/bench_reduce" "--sizes=$sizes" "--benchmark_repetitions=$repetitions"
  "--benchmark_report_aggregates_only=true" "--benchmark_enable_random_interleaving=true"
  "--benchmark_out_format=json"
  "--benchmark_out=$out/bench_reduce.json" "${bench_flags[@]}")
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
"${bench_cmd[@]}"
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

# Paths in the report are relative to the repository, not this machine.
relative() { local text=$*; echo "${text//$root\//}"; }
libraries=$(dpkg-query -W -f='${Package} ${Version}\n' libmeshoptimizer-dev libcgal-dev libbenchmark-dev 2>/dev/null |
  paste -sd, | sed 's/,/, /g' || true)
python3 "$root/scripts/bench_report_common.py" meta "$out/meta.json" \
  "script_cmd=scripts/bench_reduce.sh${commit_rev:+ --commit $commit_rev}${bench_flags[*]:+ -- ${bench_flags[*]}}" \
  "bench_cmd=$(relative "${bench_cmd[*]}")" \
  "source_state=$(relative "$source_state")" \
  "commit=$commit" \
  "libraries=$libraries" \
  "load_before=$load_before" "load_after=$load_after" \
  "environment=OMP_WAIT_POLICY=$OMP_WAIT_POLICY${OMP_NUM_THREADS:+ OMP_NUM_THREADS=$OMP_NUM_THREADS}${GLIBC_TUNABLES:+ GLIBC_TUNABLES=$GLIBC_TUNABLES}"

python3 "$root/scripts/report_reduce.py" "$out"
echo "wrote $out/README.md"
