#!/usr/bin/env bash
# The worked example without files (scripts/examples/heat_torus_insitu.sh),
# small: FEniCSx solves on 2 ranks and calls tetiso in situ at each of 3 time
# steps; each surface is a single closed torus (genus 1), and the last one is
# the bytes `tetiso run --mesh` writes for the same step's u written by
# DOLFINx as a .pvtu. Skipped (77) where FEniCSx or the tetiso Python module
# with its in-situ session is missing.
# Usage: test_heat_insitu_example.sh PATH/TO/tetiso PYTHONPATH
set -euo pipefail
tetiso=$1
export PYTHONPATH=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
/usr/bin/python3 -c "import dolfinx, gmsh" 2>/dev/null || { echo "FEniCSx (python3-dolfinx) or python3-gmsh missing"; exit 77; }
/usr/bin/python3 -c "import tetiso; tetiso.InSituSession" 2>/dev/null ||
    { echo "the tetiso Python module with its in-situ session is not built (TETISO_PYTHON, mpi4py)"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
steps=3
TETISO=$tetiso "$root/scripts/examples/heat_torus_insitu.sh" "$work" 2 0.15 "$steps" --pvtu
level=$(/usr/bin/python3 -c "import json, sys; print(repr(json.load(open(sys.argv[1]))['steps'][-1]['level']))" "$work/steps.json")
"$tetiso" run --quiet --mesh "$work/last.pvtu" --array u --node-ids vtkOriginalPointIds --level "$level" \
    -o "$work/file.vtp"
cmp "$work/surface-$steps.vtp" "$work/file.vtp"
echo "in situ == tetiso run --mesh on the step's .pvtu"
