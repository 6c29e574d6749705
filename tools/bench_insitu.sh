#!/usr/bin/env bash
# The in-situ call against the file route on the same pieces: the N^3
# lattice's 2 (RANKS) domains held in memory by the ranks of an MPI program
# in a solver's layout (bench/bench_insitu.cpp). In situ: one session,
# REPEATS calls, each rank's stages. File route: the pieces written as a
# .pvtu (appended raw binary), `mpirun -np RANKS tetiso run --mesh` on it
# (REPEATS runs), and the surface read back; the two surfaces compared with
# cmp. Wall and CPU seconds (user + system, every rank) of each.
# Usage: tools/bench_insitu.sh [N [REPEATS [RANKS]]]   (default 250 2 2; the
# pieces take ~24 N^3 bytes under $TMPDIR; TETISO and BENCH name the binaries,
# default build/core/tetiso and build/bench/bench_insitu)
# Writes results/insitu/runs-N.json and the page tools/render_results.py insitu
# makes of every runs-*.json there, results/insitu/README.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tetiso=${TETISO:-$root/build/core/tetiso}
bench=${BENCH:-$root/build/bench/bench_insitu}
n=${1:-250}
repeats=${2:-2}
ranks=${3:-2}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
load=$(cut -d' ' -f1-3 /proc/loadavg)
# The command line waits passively (core/cli/main.cpp); the solver's program
# is given the same OpenMP policy.
mpirun --oversubscribe -x OMP_WAIT_POLICY=passive -np "$ranks" "$bench" run "$n" "$work" "$repeats"
level=$(cat "$work/level.txt")
for run in $(seq "$repeats"); do
    # Wall, user and system seconds of mpirun and every rank it started.
    /usr/bin/time -f "%e %U %S" -o "$work/time-$run.txt" mpirun --oversubscribe -np "$ranks" "$tetiso" run --quiet \
        --mesh "$work/pieces.pvtu" --array f --level "$level" -o "$work/file.ply" --report "$work/run-$run.json"
done
"$bench" read "$work/file.ply" "$repeats" >"$work/read.json"
same=$(cmp -s "$work/file.ply" "$work/insitu.ply" && echo true || echo false)
out=$root/results/insitu
mkdir -p "$out"
commit=$(git -C "$root" rev-parse --short HEAD)$(git -C "$root" diff --quiet HEAD -- core bench || echo ' (with uncommitted changes)')
machine="$(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, $(free -g | awk '/^Mem:/ {print $2}') GiB"
/usr/bin/python3 - "$work" "$n" "$repeats" "$ranks" "$commit" "$machine" "$load" "$same" \
    "$(date -u +%Y-%m-%dT%H:%M:%SZ)" >"$out/runs-$n.json" <<'PY'
import json, sys
work, n, repeats, ranks, commit, machine, load, same, date = sys.argv[1:]
repeats, ranks = int(repeats), int(ranks)
insitu = json.load(open(f"{work}/insitu.json"))
runs = []
for run in range(1, repeats + 1):
    wall, user, system = map(float, open(f"{work}/time-{run}.txt").read().split()[-3:])
    report = json.load(open(f"{work}/run-{run}.json"))
    runs.append({"wall": wall, "cpu": user + system, "job": report["seconds"]})
json.dump({"command": f"tools/bench_insitu.sh {n} {repeats} {ranks}", "commit": commit, "machine": machine,
           "load_before": load, "date": date, "n": int(n), "ranks": ranks, "same_bytes": same == "true",
           "insitu": insitu, "write": json.load(open(f"{work}/write.json")), "run": runs,
           "read": json.load(open(f"{work}/read.json"))}, sys.stdout, indent=1)
PY
/usr/bin/python3 "$root/tools/render_results.py" insitu
