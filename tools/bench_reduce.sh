#!/usr/bin/env bash
# Builds the reduction benchmark (Release) and regenerates results/reduce/:
#   bench_reduce.json  Google Benchmark output: tetiso's reduce (1 and all
#                      threads) and, to the same triangle count on the N=100
#                      paper surface, meshoptimizer's meshopt_simplify, CGAL's
#                      edge_collapse and OpenMesh's Decimater (the last two
#                      where the build has them, 3 runs each), aggregates of
#                      several repetitions, quality counters
#   meta.json          command, machine, commit
#   README.md          the page, by tools/render_results.py reduce
#
# Usage: tools/bench_reduce.sh [--commit REV] [-- bench_reduce flags...]
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
# on a shared machine falls on tetiso and the baselines alike.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
source "$root/tools/bench_common.sh"

bench_parse_args "$@"

build=${BUILD_DIR:-$root/build-bench-reduce}
jobs=${JOBS:-2}
repetitions=${REPETITIONS:-10}
sizes=${SIZES:-100}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
out=$root/results/reduce

bench_select_source CMakeLists.txt core validation reference bench
if [[ -n $commit_rev ]]; then
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
fi

bench_configure
# bench_reduce is not a target where Google Benchmark or meshoptimizer is missing.
cmake --build "$build_dir" -j "$jobs" --target bench_reduce ||
  { echo "bench_reduce.sh: bench_reduce was not built (are Google Benchmark and meshoptimizer installed?)" >&2; exit 1; }
bench_run bench_reduce

libraries=$(dpkg-query -W -f='${Package} ${Version}\n' libmeshoptimizer-dev libcgal-dev libeigen3-dev libopenmesh-dev libbenchmark-dev 2>/dev/null |
  paste -sd, | sed 's/,/, /g' || true)
python3 "$root/tools/bench_meta.py" "$out/meta.json" \
  "script_cmd=$(bench_script_cmd)" \
  "bench_cmd=$(relative "${bench_cmd[*]}")" \
  "source_state=$(relative "$source_state")" \
  "commit=$commit" \
  "libraries=$libraries" \
  "load_before=$load_before" "load_after=$load_after" \
  "environment=$(bench_environment)" \
  "compile_options=$(sed -n 's/^add_compile_options("$<$<COMPILE_LANGUAGE:CXX>:\(.*\)>")$/\1/p' "$source_dir/CMakeLists.txt" |
    head -1 | tr ';' ' ')"

/usr/bin/python3 "$root/tools/render_results.py" reduce
echo "wrote $out/README.md"
