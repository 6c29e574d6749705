#!/usr/bin/env bash
# The worked example (scripts/examples/poisson_torus.sh), small: FEniCSx
# solves on 2 ranks and writes a .pvtu, tetiso's job over it on 2 ranks is a
# single closed torus (genus 1, as every level set of that solution is), and
# the same job on 1 rank writes the same bytes. Skipped (77) where FEniCSx is
# not installed. Usage: test_poisson_example.sh PATH/TO/tetiso
set -euo pipefail
tetiso=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
/usr/bin/python3 -c "import dolfinx, gmsh" 2>/dev/null || { echo "FEniCSx (python3-dolfinx) or python3-gmsh missing"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
TETISO=$tetiso "$root/scripts/examples/poisson_torus.sh" "$work" 2 0.15
level=$(/usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['u_max'] / 2)" "$work/poisson.json")
"$tetiso" run --quiet --mesh "$work/poisson.pvtu" --array u --node-ids vtkOriginalPointIds --level "$level" \
    -o "$work/one-rank.vtp"
cmp "$work/surface.vtp" "$work/one-rank.vtp"
echo "1 rank == 2 ranks"
