#!/usr/bin/env bash
# Measures the paper's experiment (its Fig. 11) on this machine: `tetiso run`
# on the N = 500 lattice, field 2cos(10x)+2sin(10y)+cos(10z) at 0.5, with 250,
# 125 and 63 domains, against the number of working MPI processes, on the CPU
# (--device cpu in every job: the paper used no GPU). Beside it, what the
# report needs to say what limits the speed-up: the machine's memory bandwidth
# (bench/bench_stream.cpp at 1 ... all threads) and, where perf can count them
# here, the job's last-level-cache misses; and the topology of every series'
# final surface (`tetiso check --strict`). tools/collect_results.py paper takes one or
# more OUTDIRs into results/paper-reproduction/ and renders
# results/paper-reproduction.md.
#
#   tools/paper_reproduction.sh OUTDIR BUDGET_S [POINTS]
#   tools/paper_reproduction.sh out/call1 550 250:1,250:2,250:15,125:15,63:15
#   EXTRAS=check tools/paper_reproduction.sh out/call2 550 125:1,63:1,125:8,63:8
#   EXTRAS=check tools/paper_reproduction.sh out/call3 550 63:1,63:4,125:4,250:4
#
# POINTS is DOMAINS:WORKERS,... run in that order (default: every series at
# 1, 2, 4, 8 and 15 workers, far more than one call's budget: give the part
# that fits). Nothing is started that would end after BUDGET_S seconds from
# the script's start, estimated from the runs before it in the same call (of
# the same series, else with as many workers; a point with neither always
# starts, so order each call's points to give every point one), so a lent
# machine's time limit is never hit mid-run; split a long sweep over calls.
#
# Environment:
#   TETISO_BIN     an already-built tetiso (else the tetiso target alone is
#                  built here in build-paper/, which needs CLI11,
#                  nlohmann-json, xxhash, METIS and muparser)
#   TETISO_PREFIX  a prefix holding those where the system has none
#   TETISO_COMMIT  the commit to record where the tree has no .git
#   STREAM_BIN     an already-built bench_stream (else compiled here with
#                  c++ -fopenmp, which needs nothing else)
#   LATTICE        N (default 500)
#   EXTRAS         which of stream,check,perf to run (default all three)
#
# Writes OUTDIR/machine.txt, OUTDIR/sweep.{json,csv,png} (every run's report,
# command, machine and commit), OUTDIR/stream.json, OUTDIR/check-dD.json (one
# per series run here), OUTDIR/perf.txt (whether perf could count). Needs python3 (standard library; the
# sweep's plot is drawn only where matplotlib exists), mpirun, lscpu.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1 budget=$2
points=${3:-250:1,250:15,125:1,125:15,63:1,63:15,250:8,125:8,63:8,250:4,125:4,63:4,250:2,125:2,63:2}
lattice=${LATTICE:-500}
extras=${EXTRAS:-stream,check,perf}
mkdir -p "$out"
start=$(date +%s)
left() { echo $((budget - ($(date +%s) - start))); }
wants() { [[ ",$extras," == *",$1,"* ]]; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

tetiso=${TETISO_BIN:-}
if [[ -z $tetiso ]]; then
  prefix=()
  [[ -n ${TETISO_PREFIX:-} ]] && prefix=(-DCMAKE_PREFIX_PATH="$TETISO_PREFIX")
  {
    cmake -S . -B build-paper -G Ninja -DCMAKE_BUILD_TYPE=Release -DTETISO_TESTS=OFF -DTETISO_BENCH=OFF \
      -DTETISO_REFERENCE=OFF "${prefix[@]}"
    cmake --build build-paper -j "$(nproc)" --target tetiso
  } >"$out/build.log" 2>&1 || { tail -30 "$out/build.log"; exit 1; }
  tetiso=build-paper/core/tetiso
  echo "built in $(($(date +%s) - start)) s"
fi
commit=${TETISO_COMMIT:-$(git rev-parse --short HEAD 2>/dev/null || echo unknown)}

{
  echo "# commit"; echo "$commit"
  echo "# date"; date -u +%Y-%m-%dT%H:%M:%SZ
  echo "# tetiso"; echo "$tetiso"
  echo "# lscpu"; lscpu
  echo "# free -g"; free -g
  echo "# nproc"; nproc
  echo "# uname -a"; uname -a
  echo "# mpirun --version"; mpirun --version | head -1
  echo "# compiler"; c++ --version 2>/dev/null | head -1 || echo none
} >"$out/machine.txt" 2>&1

# Bandwidth first: it takes seconds and the report cannot judge the speed-up
# without it, whereas a sweep cut short by the budget still gives its points.
if wants stream; then
  stream=${STREAM_BIN:-}
  if [[ -z $stream ]]; then
    stream=$out/bench_stream
    c++ -O3 -march=native -fopenmp -std=c++17 bench/bench_stream.cpp -o "$stream"
  fi
  cores=$(nproc)
  threads=$(python3 -c "import sys; n=int(sys.argv[1]); print(','.join(str(t) for t in sorted({1,2,4,6,8,10,12,14,n-1,n}) if 1<=t<=n))" "$cores")
  OMP_PROC_BIND=spread OMP_PLACES=cores "$stream" --mib 1024 --repeat 5 --threads "$threads" >"$out/stream.json"
  echo "stream: $(python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['results']; print(', '.join(f\"{x['threads']}: {x['triad_gb_s']:.0f}\" for x in r), 'GB/s triad')" "$out/stream.json")"
fi

# Last-level-cache misses of the whole machine during each job, where this
# kernel and machine let perf count them (a VM often does not).
perf_args=()
if wants perf; then
  events=LLC-load-misses,LLC-store-misses
  if command -v perf >/dev/null && perf stat -a -x , -e "$events" -o "$out/perf.txt" -- sleep 0.1 2>/dev/null &&
    ! grep -q "not supported\|not counted" "$out/perf.txt"; then
    perf_args=(--perf-events "$events")
  else
    echo "perf cannot count $events here" >>"$out/perf.txt"
  fi
fi

# Checks need a few seconds each after the sweep.
reserve=20
PYTHONUNBUFFERED=1 python3 tools/sweep_speedup.py --tetiso "$tetiso" --lattice "$lattice" --bind core \
  --commit "$commit" --points "$points" --deadline "$(($(left) - reserve))" --keep-surfaces "$out" \
  "${perf_args[@]}" --out "$out/sweep" -- --device cpu || echo "sweep failed"

for surface in "$out"/surface-d*.ply; do
  [[ -e $surface ]] || continue
  name=$(basename "$surface" .ply)
  if wants check; then
    # --strict: the JSON then lists the violated clauses of the surface
    # contract ("violations", empty when clean), and the exit status is 1
    # when there are any.
    status=0
    "$tetiso" check --strict "$surface" >"$out/check-${name#surface-}.json" 2>/dev/null || status=$?
    ((status <= 1)) || echo "check failed: $surface"
  fi
  # sweep.json's hashes identify the surface; OUTDIR keeps only small files to bring back.
  rm -f "$surface"
done

echo "done in $(($(date +%s) - start)) s"
