#!/usr/bin/env bash
# The ParaView plugin under pvbatch, with no display (its output is fetched,
# never rendered): exit 77, ctest's skip, where ParaView is not installed.
# Usage: test_paraview_plugin.sh LOAD_TETISO_PLUGIN.py   (PYTHONPATH must reach tetiso)
set -euo pipefail
loader=$1
if ! command -v pvbatch > /dev/null; then
  echo "pvbatch not found (Debian: paraview, python3-paraview): the ParaView plugin's test is skipped"
  exit 77
fi
here=$(cd "$(dirname "$0")" && pwd)
exec pvbatch "$here/paraview_plugin_check.py" "$loader" "$here/../../meshes/solver/cube-ascii.vtu"
