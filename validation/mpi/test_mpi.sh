#!/usr/bin/env bash
# The MPI job end to end: the same surface for any number of ranks, the
# topology of the D = 1 raw surface after seaming and reduction, a failing
# task ending every rank with no output, rank 0 running the last seams, and
# an unstructured mesh split into domains.
# Usage: test_mpi.sh tetiso mpiexec [test_mpi_failure]
set -u
tetiso=$1
mpiexec=${2:-mpirun}
failure_test=${3:-}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source "$(dirname "$0")/mpi_support.sh"

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

# 4. The report holds one record per task, with its seconds by stage, and the
#    timeline plot is drawn.
#    Rank 0 runs the root seam, only seams, and only while no other task runs
#    (core/job/scheduler.cpp), for any number of workers.
for k in 2 3 4; do
    python3 - "$work/k$k.json" "$k" <<'PY' && ok || fail "report of the $k-rank run"
import json, sys
r = json.load(open(sys.argv[1]))
k = int(sys.argv[2])
tasks = r["tasks"]
assert r["ranks"] == k and len(tasks) == 2 * r["domains"] - 1, (r["ranks"], len(tasks))
assert sum(t["kind"] == "domain" for t in tasks) == r["domains"]
assert {t["rank"] for t in tasks} <= set(range(k))
assert all(0 <= t["start"] <= t["end"] for t in tasks)
# Each task's stage seconds come back with its result from the rank that
# ran it: the stages of its kind, each measured inside the task's span.
for t in tasks:
    stages = t["stage_seconds"]
    want = {"generate", "extract", "reduce"} if t["kind"] == "domain" else {"merge", "region", "reduce", "splice"}
    assert set(stages) == want, t
    assert all(v >= 0 for v in stages.values()), t
    assert sum(stages.values()) <= t["end"] - t["start"] + 1e-3, t
assert r["triangles"] < r["raw_triangles"]
root = [t for t in tasks if t["domain_count"] == r["domains"]]
assert len(root) == 1 and root[0]["rank"] == 0, root
# Every domain touches an open interface and keeps raw vertices there for
# its seams; the root has none left open and keeps none.
assert all(t["samples_out"] > 0 for t in tasks if t["kind"] == "domain"), tasks
assert root[0]["samples_out"] == 0, root
for mine in (t for t in tasks if t["rank"] == 0):
    assert mine["kind"] == "seam", mine
    for other in tasks:
        if other is not mine:
            assert other["end"] <= mine["start"] + 1e-6 or other["start"] >= mine["end"] - 1e-6, (mine, other)
PY
done
if python3 -c "import matplotlib" 2>/dev/null; then
    python3 "$here/../../scripts/plot_timeline.py" "$work/k4.json" -o "$work/timeline.png" && [ -s "$work/timeline.png" ] && ok ||
        fail "timeline plot"
fi

# 5. A task that throws on rank 0 (the root seam) ends the job as a worker's
#    failure does; see test_mpi_failure.cpp.
if [ -n "$failure_test" ]; then
    for k in 2 3; do
        mpi "$k" "$failure_test" >"$work/failure.out" 2>&1 && ok ||
            fail "test_mpi_failure with $k ranks: $(head -c 600 "$work/failure.out")"
    done
fi

# 6. An unstructured TetGen mesh split by a partition file (octants of the
#    tetrahedra's centroids, written here) and by METIS: the same surface for
#    any number of ranks, sound against the whole mesh's raw surface.
mesh="$here/../../meshes/cube.1"
python3 - "$mesh" "$work/octants.part" <<'PY'
import sys
base, out = sys.argv[1], sys.argv[2]
def rows(path):
    for line in open(path):
        line = line.split("#")[0].split()
        if line: yield line
nodes = rows(base + ".node"); next(nodes)
xyz = {int(r[0]): tuple(map(float, r[1:4])) for r in nodes}
eles = rows(base + ".ele"); next(eles)
with open(out, "w") as f:
    for r in eles:
        c = [sum(xyz[int(v)][a] for v in r[1:5]) / 4 for a in range(3)]
        f.write(f"{(c[0] > 2.5) + 2 * (c[1] > 2.5) + 4 * (c[2] > 2.5)}\n")
PY
"$tetiso" extract --mesh "$mesh" --field torus -o "$work/raw-mesh.ply" || fail "extract of the mesh"
for split in "--partition $work/octants.part" "--domains 6"; do
    # shellcheck disable=SC2086
    if ! "$tetiso" run --mesh "$mesh" $split --field torus --quiet -o "$work/mesh1.ply" 2>"$work/stderr"; then
        grep -q "without METIS" "$work/stderr" && [ "$split" = "--domains 6" ] && continue
        fail "mesh run ($split): $(head -3 "$work/stderr")"
        continue
    fi
    for k in 2 3; do
        # shellcheck disable=SC2086
        if mpi "$k" "$tetiso" run --mesh "$mesh" $split --field torus --quiet -o "$work/mesh$k.ply"; then
            cmp -s "$work/mesh1.ply" "$work/mesh$k.ply" && ok || fail "mesh ($split): $k ranks differ from 1"
        else
            fail "mesh run ($split) with $k ranks"
        fi
    done
    # Half the mesh's spacing (its mean edge length, 0.43).
    "$tetiso" check "$work/mesh1.ply" --against "$work/raw-mesh.ply" >"$work/check.json" &&
        python3 "$here/expect_sound.py" "$work/check.json" 0.215 --absolute && ok ||
        fail "mesh ($split): $(head -c 400 "$work/check.json")"
done

# 7. The octant partition written as one file per domain: on any number of
#    ranks, each reading only its domains, the job over the mesh, byte for byte.
if "$tetiso" split --mesh "$mesh" --partition "$work/octants.part" --field torus --quiet -o "$work/octants" &&
    "$tetiso" run --mesh "$mesh" --partition "$work/octants.part" --field torus --quiet -o "$work/whole.ply"; then
    for k in 1 3; do
        if mpi "$k" "$tetiso" run --split "$work/octants" --quiet -o "$work/split$k.ply"; then
            cmp -s "$work/whole.ply" "$work/split$k.ply" && ok || fail "split: $k ranks differ from the job over the mesh"
        else
            fail "run over the split with $k ranks"
        fi
    done
else
    fail "split of the mesh, or the job over it"
fi

# 8. --device auto: the same bytes as --device cpu, with one rank and with
#    three. Where there is no GPU every task runs on the CPU; the report says
#    where each ran, what the node's resource manager predicted and how long
#    the task waited, and sums each device's share.
auto_args=(run --lattice 40 --domains 27 --field gyroid --quiet)
"$tetiso" "${auto_args[@]}" --device cpu -o "$work/cpu.ply" || fail "--device cpu run"
have_gpu=0
"$tetiso" extract --lattice 8 --device gpu -o "$work/probe.ply" 2>/dev/null && have_gpu=1
for k in 1 3; do
    if [ "$k" -eq 1 ]; then
        "$tetiso" "${auto_args[@]}" --device auto -o "$work/auto1.ply" --report "$work/auto1.json"
    else
        mpi "$k" "$tetiso" "${auto_args[@]}" --device auto -o "$work/auto$k.ply" --report "$work/auto$k.json"
    fi || { fail "--device auto with $k ranks"; continue; }
    cmp -s "$work/cpu.ply" "$work/auto$k.ply" && ok || fail "--device auto with $k ranks differs from --device cpu"
    python3 - "$work/auto$k.json" "$have_gpu" <<'PY' && ok || fail "report of --device auto with $k ranks"
import json, sys
r = json.load(open(sys.argv[1]))
have_gpu = sys.argv[2] == "1"
tasks = r["tasks"]
assert r["device"] == "auto", r["device"]
for t in tasks:
    assert t["device"] == "cpu" or (have_gpu and t["device"].startswith("gpu ") and t["kind"] == "domain"), t
    assert t["wait_seconds"] >= 0, t
    # Every task a worker ran was placed by its node's manager, with a prediction.
    assert t["predicted_seconds"] > 0 or (t["rank"] == 0 and r["ranks"] > 1), t
summary = r["devices"]
assert sum(d["tasks"] for d in summary.values()) == len(tasks), summary
assert sum(d["domain_tasks"] for d in summary.values()) == r["domains"], summary
if not have_gpu:
    assert list(summary) == ["cpu"], summary
PY
done
if python3 -c "import matplotlib" 2>/dev/null; then
    python3 "$here/../../scripts/plot_timeline.py" "$work/auto3.json" -o "$work/auto.png" && [ -s "$work/auto.png" ] && ok ||
        fail "timeline plot of --device auto"
fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
