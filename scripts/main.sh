#!/usr/bin/env bash
# Installs, builds and runs the main job, `tetiso run`, on the paper's test
# problem: 2cos(10x)+2sin(10y)+cos(10z) = 0.5 on a 250^3 lattice split into
# 125 domains; every domain is extracted and reduced, and the pieces are
# seamed pairwise and reduced near each seam until one surface remains.
# Writes out/surface.vtp (open it in ParaView) and out/report.json (sizes,
# seconds, one record per task: scripts/plot_timeline.py draws them).
#
# With MPI: one controlling rank and one worker per core (the controller
# mostly waits on messages). Without MPI, or with a tetiso built without it,
# one process runs every task.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install.sh
mkdir -p out
args=(run --lattice 250 --domains 125 --field paper -o out/surface.vtp --report out/report.json)
if command -v mpirun >/dev/null && ldd build/core/tetiso | grep -q libmpi; then
  # Debian's Open MPI refuses root unless told; install.sh runs as root.
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    mpirun --oversubscribe -np $(($(nproc) + 1)) build/core/tetiso "${args[@]}"
else
  build/core/tetiso "${args[@]}"
fi
echo "wrote out/surface.vtp and out/report.json"
