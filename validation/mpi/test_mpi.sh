#!/usr/bin/env bash
# The MPI job end to end: the same surface for any number of ranks, the
# topology of the D = 1 raw surface after seaming and reduction, and a failing
# task ending every rank with no output. Usage: test_mpi.sh tetiso mpiexec
set -u
tetiso=$1
mpiexec=${2:-mpirun}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
passed=0
failures=0
ok() { passed=$((passed + 1)); }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
mpi() { local k=$1; shift; timeout 300 "$mpiexec" --oversubscribe -np "$k" "$@"; }

# 1. Bit-identical output for K = 1 (no launcher), 2, 3, 4 ranks.
args=(run --lattice 40 --domains 27 --field gyroid --quiet)
"$tetiso" "${args[@]}" -o "$work/k1.ply" || fail "single-process run"
for k in 2 3 4; do
    if mpi "$k" "$tetiso" "${args[@]}" -o "$work/k$k.ply" --report "$work/k$k.json"; then
        cmp -s "$work/k1.ply" "$work/k$k.ply" && ok || fail "output with $k ranks differs from 1 rank"
    else
        fail "run with $k ranks"
    fi
done

# 2. After seaming and reduction, D domains give the per-component topology
#    of the unreduced single-domain surface, and a sound mesh.
for field in paper torus; do
    "$tetiso" extract --lattice 50 --domains 1 --field "$field" -o "$work/raw-$field.ply" || fail "extract $field"
    for d in 8 27 63; do
        out="$work/$field-$d.ply"
        if mpi 3 "$tetiso" run --lattice 50 --domains "$d" --field "$field" --quiet -o "$out"; then
            "$tetiso" check "$out" --against "$work/raw-$field.ply" >"$work/check.json" &&
            python3 "$here/expect_sound.py" "$work/check.json" 0.5 && ok ||
            fail "$field with $d domains: $(cat "$work/check.json" | head -c 400)"
        else
            fail "run of $field with $d domains"
        fi
    done
done

# 3. A task that throws (a field that is NaN in part of the cube) ends the
#    job on every rank: non-zero status, no output, no hang.
start=$(date +%s)
mpi 3 "$tetiso" run --lattice 30 --domains 8 --field "sqrt(x-4)" -o "$work/failed.ply" 2>"$work/stderr"
status=$?
elapsed=$(($(date +%s) - start))
if [ "$status" -ne 0 ] && [ "$status" -ne 124 ] && [ ! -e "$work/failed.ply" ] && [ "$elapsed" -lt 60 ] &&
    grep -q "failed on rank" "$work/stderr" && ! ls "$work" | grep -q "failed.ply.tmp"; then
    ok
else
    fail "failing task: status $status after ${elapsed}s: $(head -3 "$work/stderr")"
fi

# 4. The report holds one record per task, and the timeline plot is drawn.
python3 - "$work/k4.json" <<'PY' && ok || fail "report of the 4-rank run"
import json, sys
r = json.load(open(sys.argv[1]))
tasks = r["tasks"]
assert r["ranks"] == 4 and len(tasks) == 2 * r["domains"] - 1, (r["ranks"], len(tasks))
assert sum(t["kind"] == "domain" for t in tasks) == r["domains"]
assert {t["rank"] for t in tasks} <= {1, 2, 3}
assert all(0 <= t["start"] <= t["end"] for t in tasks)
assert r["triangles"] < r["raw_triangles"]
PY
if python3 -c "import matplotlib" 2>/dev/null; then
    python3 "$here/../../scripts/plot_timeline.py" "$work/k4.json" -o "$work/timeline.png" && [ -s "$work/timeline.png" ] && ok ||
        fail "timeline plot"
fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
