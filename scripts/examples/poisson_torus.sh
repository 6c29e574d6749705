#!/usr/bin/env bash
# A solver's result through tetiso, end to end: Gmsh meshes a solid torus,
# FEniCSx (DOLFINx) solves -laplace(u) = 1 with u = 0 on its surface on
# RANKS MPI ranks and writes u as a .pvtu (one piece per rank), and
# `tetiso run` extracts and reduces the level set u = max(u)/2, a torus,
# seaming the pieces by DOLFINx's global node ids (vtkOriginalPointIds).
#
# Usage: scripts/examples/poisson_torus.sh [OUTDIR [RANKS [SIZE]]]
#   OUTDIR  where to write (default out/poisson): poisson.pvtu and its
#           pieces, surface.vtp, report.json, check.json
#   RANKS   solver ranks, and tetiso's (default 4)
#   SIZE    the mesh size (default 0.05: about 60,000 tetrahedra)
# TETISO names the tetiso binary (default build/core/tetiso).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-out/poisson}
ranks=${2:-4}
size=${3:-0.05}
tetiso=${TETISO:-$root/build/core/tetiso}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

mkdir -p "$out"
mpirun -np "$ranks" /usr/bin/python3 "$root/scripts/examples/poisson_torus.py" "$out" --size "$size" \
    2> >(grep -v "^INFO:root:" >&2)
level=$(/usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['u_max'] / 2)" "$out/poisson.json")
echo "poisson_torus.sh: level $level"
mpirun -np "$ranks" "$tetiso" run --quiet --mesh "$out/poisson.pvtu" --array u --node-ids vtkOriginalPointIds \
    --level "$level" -o "$out/surface.vtp" --report "$out/report.json"
"$tetiso" check "$out/surface.vtp" >"$out/check.json"
/usr/bin/python3 - "$out/check.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))["topology"]
genus = [c["genus"] for c in t["per_component"]]
print(f"poisson_torus.sh: {t['triangles']} triangles, {t['components']} component(s), genus {genus}, "
      f"closed {t['closed']}, manifold {t['manifold']}")
sys.exit(0 if t["components"] == 1 and genus == [1] and t["closed"] and t["manifold"] else 1)
PY
