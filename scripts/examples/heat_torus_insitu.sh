#!/usr/bin/env bash
# The worked example without files: FEniCSx (DOLFINx) solves the heat
# equation on a solid torus on RANKS MPI ranks and, at every step of its time
# loop, gets the reduced isosurface u = max(u)/2 from tetiso in situ
# (tetiso.InSituSession over the solver's communicator and arrays); only the
# surfaces are written. Each surface must be one closed, oriented torus
# (genus 1), as every level set of u is.
#
# Usage: scripts/examples/heat_torus_insitu.sh [OUTDIR [RANKS [SIZE [STEPS]]]]
#   OUTDIR  where to write (default out/heat): surface-S.vtp per step, steps.json
#   RANKS   solver ranks (default 4)
#   SIZE    the mesh size (default 0.1)
#   STEPS   time steps (default 5)
# TETISO names the tetiso binary (default build/core/tetiso), which checks the
# surfaces; PYTHONPATH reaches the tetiso module (default build/python).
# Further arguments go to heat_torus_insitu.py (e.g. --pvtu).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-out/heat}
ranks=${2:-4}
size=${3:-0.1}
steps=${4:-5}
shift $(($# < 4 ? $# : 4))
tetiso=${TETISO:-$root/build/core/tetiso}
export PYTHONPATH=${PYTHONPATH:-$root/build/python}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

mkdir -p "$out"
mpirun -np "$ranks" -x PYTHONPATH /usr/bin/python3 "$root/scripts/examples/heat_torus_insitu.py" "$out" \
    --size "$size" --steps "$steps" "$@" 2> >(grep -v "^INFO:root:" >&2)
for step in $(seq "$steps"); do
    "$tetiso" check "$out/surface-$step.vtp" >"$out/check-$step.json"
    /usr/bin/python3 - "$out/check-$step.json" "$step" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))["topology"]
genus = [c["genus"] for c in t["per_component"]]
print(f"heat_torus_insitu.sh: step {sys.argv[2]}: {t['triangles']} triangles, {t['components']} component(s), "
      f"genus {genus}, closed {t['closed']}, manifold {t['manifold']}")
sys.exit(0 if t["components"] == 1 and genus == [1] and t["closed"] and t["manifold"] else 1)
PY
done
