#!/usr/bin/env bash
# The job over an unstructured mesh: makes a TetGen mesh of the paper's cube
# (volume bound VOLUME per tetrahedron), extracts the paper field's surface
# from it whole, runs `tetiso run --mesh` with 1 and with D domains (METIS)
# on NP ranks, and checks both results against the raw surface.
# Usage: scripts/mesh_job.sh [VOLUME=0.0005] [D=32] [NP=3]; outputs in out/mesh/.
set -euo pipefail
cd "$(dirname "$0")/.."
volume=${1:-0.0005}
domains=${2:-32}
ranks=${3:-3}
tetiso=${TETISO:-build/core/tetiso}
work=out/mesh
mkdir -p "$work"
cp meshes/cube.poly "$work/"
tetgen -pq1.3a"$volume"Q "$work/cube.poly"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
"$tetiso" extract --mesh "$work/cube.1" --field paper -o "$work/raw.ply"
for d in 1 "$domains"; do
    /usr/bin/time -f "D = $d: %e s wall" \
        mpirun --oversubscribe -np "$ranks" "$tetiso" run --mesh "$work/cube.1" --domains "$d" --field paper \
        --quiet -o "$work/run$d.ply" --report "$work/run$d.json"
    "$tetiso" check "$work/run$d.ply" --against "$work/raw.ply" >"$work/check$d.json"
    python3 - "$work/run$d.json" "$work/check$d.json" <<'PY'
import json, sys
run, check = (json.load(open(p)) for p in sys.argv[1:3])
t, a = check["topology"], check["against"]
print(f"D = {run['domains']}: {run['tets']} tets, spacing {run['spacing']:.4f}, raw {run['raw_triangles']} -> "
      f"{run['triangles']} triangles, job {run['seconds']['job']:.2f} s; same signatures {a['same_signatures']}, "
      f"manifold {t['manifold']}, degenerate {t['degenerate_triangles']}, self-intersections "
      f"{check.get('self_intersections')}, Hausdorff {a['hausdorff']['symmetric']:.4f}")
PY
done
