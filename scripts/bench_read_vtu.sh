#!/usr/bin/env bash
# Time to read a 10^6-node .vtu piece (100^3 lattice nodes, 5.8 M
# tetrahedra; appended raw binary, UInt64 headers, Int64 connectivity,
# Float64 points and field, as ParaView writes large pieces), and the same
# zlib-compressed: the "read" seconds of `tetiso extract --report` (file to
# domain: the reader and the orientation check), one thread, REPEATS runs.
# Usage: scripts/bench_read_vtu.sh [REPEATS]   (writes ~270 MB under $TMPDIR)
# Writes results/solver-read/README.md: the figures with the command,
# machine, commit and date.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tetiso=${TETISO:-$root/build/core/tetiso}
repeats=${1:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
load=$(cut -d' ' -f1-3 /proc/loadavg)
rows=()
for variant in raw zlib; do
    /usr/bin/python3 "$root/scripts/bench_read_vtu.py" "$work/piece.vtu" 100 $([ $variant = zlib ] && echo --zlib)
    size=$(stat -c %s "$work/piece.vtu")
    times=()
    for _ in $(seq "$repeats"); do
        "$tetiso" extract --mesh "$work/piece.vtu" --array distance --level 1.5 -o "$work/s.ply" --report "$work/r.json"
        times+=("$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seconds']['read'])" "$work/r.json")")
    done
    echo "$variant: $size bytes, read seconds: ${times[*]}"
    label=$([ $variant = zlib ] && echo "appended raw, zlib blocks of 32 KiB" || echo "appended raw")
    rows+=("$(/usr/bin/python3 -c '
import statistics, sys
label, size, times = sys.argv[1], int(sys.argv[2]), [float(t) for t in sys.argv[3:]]
print(f"| {label} | {size:,} | {statistics.median(times):.3f} | " + ", ".join(f"{t:.3f}" for t in times) + " |")
' "$label" "$size" "${times[@]}")")
done
out=$root/results/solver-read/README.md
mkdir -p "$(dirname "$out")"
{
    echo "# Reading a solver's piece"
    echo
    echo "A 10⁶-node piece (100³ lattice nodes, 5.8 M tetrahedra) as ParaView writes large pieces — appended raw"
    echo "binary, UInt64 headers, Int64 connectivity and offsets, Float64 points and field — read by \`tetiso extract"
    echo "--mesh piece.vtu --array distance\` into one domain: the report's \`seconds.read\` (file to domain: parsing,"
    echo "every check, the orientation of every tetrahedron), one thread, $repeats runs each. Target: ≤ 0.2 s for the raw piece."
    echo
    echo "| piece | bytes | median s | each run, s |"
    echo "|---|---|---|---|"
    printf '%s\n' "${rows[@]}"
    echo
    echo "The raw piece is mapped rather than read, its arrays converted straight from the mapping and its Int64"
    echo "connectivity written into 32-bit indices in one pass; a compressed piece is bound by zlib's inflate."
    echo
    echo "- Command: \`scripts/bench_read_vtu.sh $repeats\`"
    echo "- Commit: \`$(git -C "$root" rev-parse --short HEAD)\`$(git -C "$root" diff --quiet HEAD -- core || echo ' (with uncommitted changes to core/)')"
    echo "- Machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs, load average before the run $load"
    echo "- Date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
} >"$out"
echo "wrote $out"
