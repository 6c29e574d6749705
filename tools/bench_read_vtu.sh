#!/usr/bin/env bash
# Time to read a 10^6-node .vtu piece (100^3 lattice nodes, 5.8 M
# tetrahedra; appended raw binary, UInt64 headers, Int64 connectivity,
# Float64 points and field, as ParaView writes large pieces), and the same
# zlib-compressed: the "read" seconds of `tetiso extract --report` (file to
# domain: the reader and the orientation check), one thread, REPEATS runs.
# Usage: tools/bench_read_vtu.sh [REPEATS]   (writes ~270 MB under $TMPDIR;
# TETISO names the binary, default build/core/tetiso)
# Writes results/solver-read/runs.json (every run's seconds, the command,
# machine, commit and date) and the page tools/render_results.py solver-read makes
# of it, results/solver-read/README.md.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tetiso=${TETISO:-$root/build/core/tetiso}
repeats=${1:-5}
lattice=100 # nodes per axis: a 10^6-node piece
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
load=$(cut -d' ' -f1-3 /proc/loadavg)
for variant in raw zlib; do
    /usr/bin/python3 "$root/tools/bench_read_vtu.py" "$work/piece.vtu" "$lattice" $([ $variant = zlib ] && echo --zlib)
    stat -c %s "$work/piece.vtu" >"$work/$variant.bytes"
    for run in $(seq "$repeats"); do
        "$tetiso" extract --mesh "$work/piece.vtu" --array distance --level 1.5 -o "$work/s.ply" \
            --report "$work/$variant.$run.json"
    done
done
out=$root/results/solver-read
mkdir -p "$out"
commit=$(git -C "$root" rev-parse --short HEAD)$(git -C "$root" diff --quiet HEAD -- core || echo ' (with uncommitted changes to core/)')
machine="$(lscpu | sed -n 's/^Model name: *//p'), $(nproc) CPUs"
/usr/bin/python3 - "$work" "$repeats" "$lattice" "$commit" "$machine" "$load" "$(date -u +%Y-%m-%dT%H:%M:%SZ)" \
    >"$out/runs.json" <<'PY'
import json, sys
work, repeats, lattice, commit, machine, load, date = sys.argv[1:]
repeats, lattice = int(repeats), int(lattice)
labels = {"raw": "appended raw", "zlib": "appended raw, zlib blocks of 32 KiB"}
pieces = []
for variant, label in labels.items():
    reports = [json.load(open(f"{work}/{variant}.{run}.json")) for run in range(1, repeats + 1)]
    tets = reports[0]["tets"]  # the same mesh in both encodings
    pieces.append({"variant": variant, "label": label, "bytes": int(open(f"{work}/{variant}.bytes").read()),
                   "seconds": [r["seconds"]["read"] for r in reports]})
json.dump({"command": f"tools/bench_read_vtu.sh {repeats}", "commit": commit, "machine": machine,
           "load_before": load, "date": date, "lattice": lattice, "tetrahedra": tets, "repeats": repeats,
           "pieces": pieces}, sys.stdout, indent=1)
PY
/usr/bin/python3 "$root/tools/render_results.py" solver-read
