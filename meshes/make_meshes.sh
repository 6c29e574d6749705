#!/usr/bin/env bash
# Regenerates the committed TetGen meshes from their input geometry. Needs
# Debian's tetgen (scripts/install.sh installs it). The outputs are committed
# so that tests never depend on TetGen's version.
#
#   cube.1.node / cube.1.ele   the paper's cube [0,5]^3: quality mesh
#                              (radius-edge ratio <= 1.3, volume <= 0.02)
set -euo pipefail
cd "$(dirname "$0")"
command -v tetgen >/dev/null || { echo "make_meshes.sh: tetgen not found (apt-get install tetgen)" >&2; exit 2; }
tetgen -pq1.3a0.02Q cube.poly
rm -f cube.1.face cube.1.edge cube.1.neigh cube.1.smesh
