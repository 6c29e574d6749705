#!/usr/bin/env bash
# Time to read a 10^6-node .vtu piece (100^3 lattice nodes, 5.8 M
# tetrahedra; appended raw binary, UInt64 headers, Int64 connectivity,
# Float64 points and field, as ParaView writes large pieces), and the same
# zlib-compressed: the "read" seconds of `tetiso extract --report` (file to
# domain: the reader and the orientation check), one thread, REPEATS runs.
# Usage: scripts/bench_read_vtu.sh [REPEATS]   (writes ~270 MB under $TMPDIR)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tetiso=${TETISO:-$root/build/core/tetiso}
repeats=${1:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for variant in raw zlib; do
    /usr/bin/python3 "$root/scripts/bench_read_vtu.py" "$work/piece.vtu" 100 $([ $variant = zlib ] && echo --zlib)
    size=$(stat -c %s "$work/piece.vtu")
    times=()
    for _ in $(seq "$repeats"); do
        "$tetiso" extract --mesh "$work/piece.vtu" --array distance --level 1.5 -o "$work/s.ply" --report "$work/r.json"
        times+=("$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seconds']['read'])" "$work/r.json")")
    done
    echo "$variant: $size bytes, read seconds: ${times[*]}"
done
