#!/usr/bin/env bash
# tetiso.InSituSession on 2 ranks (insitu_check.py) against `tetiso run
# --mesh` on the same pieces written as a .pvtu: the same bytes.
# Usage: test_insitu.sh TETISO MPIEXEC PYTHON   (PYTHONPATH must reach tetiso)
set -euo pipefail
tetiso=$1
mpiexec=$2
python=$3
here=$(cd "$(dirname "$0")" && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
timeout 300 "$mpiexec" --oversubscribe -np 2 "$python" "$here/insitu_check.py" "$here/../../meshes/solver/cube-ascii.vtu" "$out"
"$tetiso" run --mesh "$out/pieces.pvtu" --array distance --level 3 --quiet -o "$out/run.ply"
for surface in insitu.ply insitu-again.ply insitu-written.ply; do
  cmp "$out/run.ply" "$out/$surface" || { echo "$surface differs from tetiso run --mesh's surface"; exit 1; }
done
echo "in situ on 2 ranks: tetiso run --mesh's bytes"
