#!/usr/bin/env bash
# Builds the tetiso command alone (no tests, benchmarks or baselines) in
# build-speedup/, records the machine, then runs scripts/sweep_speedup.py once
# per remaining argument (each argument is one sweep's options, word-split),
# within one overall time budget: each sweep gets --deadline set to what is
# left of BUDGET_S, so a lent machine's time limit is never hit mid-run.
#
#   scripts/bench_speedup.sh OUTDIR BUDGET_S "SWEEP OPTIONS" ["SWEEP OPTIONS" ...]
#   scripts/bench_speedup.sh out 540 "--lattice 500 --points 125:15 --bind core --out out/t-core"
#
# TETISO_COMMIT is recorded as the commit where the tree has no .git.
# TETISO_PREFIX names a prefix holding CLI11, nlohmann-json and xxhash.h where the
# system has none (e.g. headers carried to a machine without a registry).
# Writes OUTDIR/machine.txt and OUTDIR/build.log; the sweeps write where their
# --out says.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1 budget=$2
shift 2
mkdir -p "$out"
start=$(date +%s)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

prefix=()
[ -n "${TETISO_PREFIX:-}" ] && prefix=(-DCMAKE_PREFIX_PATH="$TETISO_PREFIX")
{
    cmake -S . -B build-speedup -G Ninja -DCMAKE_BUILD_TYPE=Release -DTETISO_TESTS=OFF -DTETISO_BENCH=OFF \
        -DTETISO_REFERENCE=OFF "${prefix[@]}"
    cmake --build build-speedup -j "$(nproc)" --target tetiso
} >"$out/build.log" 2>&1 || { tail -30 "$out/build.log"; exit 1; }
echo "built in $(($(date +%s) - start)) s"

{
    echo "# commit"; echo "${TETISO_COMMIT:-$(git rev-parse HEAD 2>/dev/null || echo unknown)}"
    echo "# date"; date -u +%Y-%m-%dT%H:%M:%SZ
    echo "# lscpu"; lscpu
    echo "# free -g"; free -g
    echo "# nproc"; nproc
    echo "# uname -a"; uname -a
    echo "# compiler"; c++ --version | head -1
    echo "# mpirun --version"; mpirun --version | head -1
    echo "# build"; grep -E "CMAKE_BUILD_TYPE|CMAKE_CXX_FLAGS_RELEASE|MPI_CXX_FOUND|OpenMP_CXX_FOUND" \
        build-speedup/CMakeCache.txt || true
} >"$out/machine.txt" 2>&1

for sweep in "$@"; do
    left=$((budget - ($(date +%s) - start)))
    if [ "$left" -le 0 ]; then
        echo "budget spent: not run: $sweep"
        continue
    fi
    # shellcheck disable=SC2086  # one argument holds one sweep's options
    PYTHONUNBUFFERED=1 python3 scripts/sweep_speedup.py --tetiso build-speedup/core/tetiso --deadline "$left" $sweep ||
        echo "sweep failed: $sweep"
done
echo "done in $(($(date +%s) - start)) s"
