# shellcheck shell=bash
# The drivers' variables are read and set here, out of shellcheck's sight.
# shellcheck disable=SC2034,SC2154
# Sourced by tools/bench_extract.sh and tools/bench_reduce.sh: how a
# benchmark driver takes its arguments, picks and builds the source it
# measures, runs its program and describes the run. One copy, so that every
# results/*/meta.json records a run the same way and a fix to the snapshot
# export reaches both drivers.
#
# The functions read and set the driver's own variables, named at each one;
# the driver sets root (the repository), build (its build directory), out (its
# results directory), sizes and repetitions, and runs under set -euo pipefail.

# Takes [--commit REV] [-- program flags...]; sets commit_rev and bench_flags.
bench_parse_args() {
  commit_rev=""
  bench_flags=()
  while [[ $# -gt 0 ]]; do
    case "$1" in
      --commit) commit_rev=$2; shift 2 ;;
      --) shift; bench_flags=("$@"); break ;;
      *) echo "${0##*/}: unknown argument $1" >&2; exit 2 ;;
    esac
  done
}

# Sets commit, source_dir, build_dir and source_state. With --commit, the
# committed tree is measured, exported with git archive under $build once per
# commit, so that what was measured is exactly what the report names however
# the checkout changes meanwhile. Without it the working tree is, and
# source_state lists the uncommitted changes among the given paths: those that
# go into the driver's programs.
bench_select_source() {
  if [[ -n $commit_rev ]]; then
    commit=$(git rev-parse --verify "$commit_rev^{commit}")
    source_dir=$build/snapshot-${commit:0:12}
    build_dir=$build/snapshot-${commit:0:12}-build
    if [[ ! -d $source_dir ]]; then
      # Moved into place only once complete: an interrupted export is never
      # taken for a finished snapshot.
      mkdir -p "$source_dir.tmp"
      git archive "$commit" | tar -x -C "$source_dir.tmp"
      mv "$source_dir.tmp" "$source_dir"
    fi
    source_state="committed tree $commit (exported with git archive)"
  else
    commit=$(git rev-parse HEAD)
    source_dir=$root
    build_dir=$build
    local changed
    changed=$(git status --porcelain -- "$@" | awk '{print $2}' | paste -sd' ')
    source_state="working tree on $commit${changed:+, with uncommitted changes in: $changed}"
  fi
}

# Configures $build_dir from $source_dir: Release, benchmarks and baselines
# on, tests off (they would only lengthen the build).
bench_configure() {
  cmake -S "$source_dir" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DTETISO_BENCH=ON -DTETISO_REFERENCE=ON -DTETISO_TESTS=OFF >/dev/null
}

# Runs $build_dir/bench/PROGRAM on $sizes with $repetitions repetitions,
# interleaved in random order so that other load on a shared machine falls on
# every case alike, into $out/PROGRAM.json. Sets bench_cmd, load_before and
# load_after for meta.json.
bench_run() {
  local program=$1
  mkdir -p "$out"
  bench_cmd=("$build_dir/bench/$program" "--sizes=$sizes" "--benchmark_repetitions=$repetitions"
    "--benchmark_report_aggregates_only=true" "--benchmark_enable_random_interleaving=true"
    "--benchmark_out_format=json"
    "--benchmark_out=$out/$program.json" "${bench_flags[@]}")
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  "${bench_cmd[@]}"
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)
}

# Paths in the report are relative to the repository, not this machine.
relative() { local text=$*; echo "${text//$root\//}"; }

# The driver's command line as the report prints it, to rerun the same way.
bench_script_cmd() {
  echo "tools/${0##*/}${commit_rev:+ --commit $commit_rev}${bench_flags[*]:+ -- ${bench_flags[*]}}"
}

# The environment variables that change how the programs' threads behave.
bench_environment() {
  echo "OMP_WAIT_POLICY=$OMP_WAIT_POLICY${OMP_NUM_THREADS:+ OMP_NUM_THREADS=$OMP_NUM_THREADS}${GLIBC_TUNABLES:+ GLIBC_TUNABLES=$GLIBC_TUNABLES}"
}
