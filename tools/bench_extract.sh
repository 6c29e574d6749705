#!/usr/bin/env bash
# Builds the extraction benchmarks (Release) and regenerates results/extract/:
#   bench_extract.json  Google Benchmark output: tetiso (1 and all threads) and
#                       VTK's vtkContour3DLinearGrid on the N=100 and N=200
#                       lattices, aggregates of several repetitions
#   memory.jsonl        peak resident memory, one fresh process per line
#   meta.json           command, machine, commit
#   README.md           the page, by tools/render_results.py extract
#
# Usage: tools/bench_extract.sh [--commit REV] [-- bench_extract flags...]
#   --commit REV  measure the committed tree REV (exported with git archive
#                 into the build directory) instead of the working tree, so
#                 that the report names exactly what was measured even while
#                 others edit the checkout. Committed results use --commit HEAD.
# Environment: BUILD_DIR (default build-bench), JOBS (default 2),
#   REPETITIONS (default 10), SIZES (default 100,200), MEMORY_N (default 100).
#   OMP_WAIT_POLICY (default passive).
# Repetitions of all cases run interleaved in random order, so that other load
# on a shared machine falls on tetiso and VTK alike. OpenMP threads wait
# passively by default: libgomp's active spinning, on cores that other
# processes also use, turns every barrier into a wait for a descheduled thread
# (2 threads at N=40 took 52 ms spinning, 15 ms passive, 17 ms on one thread).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
source "$root/tools/bench_common.sh"

bench_parse_args "$@"

build=${BUILD_DIR:-$root/build-bench}
jobs=${JOBS:-2}
repetitions=${REPETITIONS:-10}
sizes=${SIZES:-100,200}
memory_n=${MEMORY_N:-100}
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
out=$root/results/extract

bench_select_source CMakeLists.txt core reference bench
bench_configure
cmake --build "$build_dir" -j "$jobs" --target extract_benchmarks
bin=$build_dir/bench
if [[ ! -x $bin/bench_extract ]]; then
  echo "bench_extract.sh: bench_extract was not built (is Google Benchmark installed?)" >&2
  exit 1
fi

bench_run bench_extract

# Peak memory: a fresh process per measurement, so nothing else is resident.
memory_cmds=("$bin/bench_extract_memory --n=$memory_n --method=tetiso --threads=1"
  "$bin/bench_extract_memory --n=$memory_n --method=tetiso --threads=$(nproc)")
if [[ -x $bin/bench_extract_memory_vtk ]]; then
  memory_cmds+=("$bin/bench_extract_memory_vtk --n=$memory_n --method=vtk --threads=1")
fi
: >"$out/memory.jsonl"
for cmd in "${memory_cmds[@]}"; do
  $cmd >>"$out/memory.jsonl"
done

BENCH_CMD=$(relative "${bench_cmd[*]}") \
MEMORY_CMDS=$(relative "$(printf '%s\n' "${memory_cmds[@]}")") \
SCRIPT_CMD=$(bench_script_cmd) \
SOURCE_STATE=$(relative "$source_state") \
COMMIT=$commit \
CPU_MODEL=$(lscpu | sed -n 's/^Model name:[[:space:]]*//p' | head -n1) \
CPUS=$(nproc) \
CORES_PER_SOCKET=$(lscpu | sed -n 's/^Core(s) per socket:[[:space:]]*//p' | head -n1) \
THREADS_PER_CORE=$(lscpu | sed -n 's/^Thread(s) per core:[[:space:]]*//p' | head -n1) \
MEMORY=$(free -g | awk '/^Mem:/ {print $2 " GiB"}') \
KERNEL=$(uname -sr) \
COMPILER=$(c++ --version | head -n1) \
LOAD_BEFORE=$load_before LOAD_AFTER=$load_after \
ENVIRONMENT=$(bench_environment) \
DATE=$(date -u +%Y-%m-%dT%H:%M:%SZ) \
python3 - "$out/meta.json" <<'EOF'
import json, os, sys
keys = ["SCRIPT_CMD", "BENCH_CMD", "MEMORY_CMDS", "SOURCE_STATE", "COMMIT", "CPU_MODEL", "CPUS",
        "CORES_PER_SOCKET", "THREADS_PER_CORE", "MEMORY", "KERNEL", "COMPILER", "LOAD_BEFORE",
        "LOAD_AFTER", "ENVIRONMENT", "DATE"]
meta = {key.lower(): os.environ[key] for key in keys}
meta["memory_cmds"] = meta["memory_cmds"].splitlines()
with open(sys.argv[1], "w") as f:
    json.dump(meta, f, indent=2)
    f.write("\n")
EOF

/usr/bin/python3 "$root/tools/render_results.py" extract
echo "wrote $out/README.md"
