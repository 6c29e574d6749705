#!/usr/bin/env bash
# The job over an unstructured mesh held whole on every rank (`run --mesh`)
# against the same partition written as one file per domain (`tetiso split`,
# then `run --split`): each rank's peak memory, the wall time, and whether the
# surfaces are the same bytes. Makes a TetGen mesh of the paper's cube with
# volume bound VOLUME per tetrahedron and splits it into D domains by METIS.
# Usage: tools/split_job.sh [VOLUME=0.00015] [D=32] [NP=3]; outputs in out/split/.
set -euo pipefail
cd "$(dirname "$0")/.."
volume=${1:-0.00015}
domains=${2:-32}
ranks=${3:-3}
tetiso=$(realpath "${TETISO:-build/core/tetiso}")
rss=$(realpath tools/rank_peak_rss.py)
work=out/split
rm -rf "$work"
mkdir -p "$work"
cp meshes/cube.poly "$work/"
tetgen -pq1.3a"$volume"Q "$work/cube.poly"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
start=$(date +%s.%N)
"$tetiso" split --mesh "$work/cube.1" --domains "$domains" --field paper --quiet -o "$work/domains"
split_seconds=$(python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$start" "$(date +%s.%N)")
for mode in mesh split; do
    if [ "$mode" = mesh ]; then source=(--mesh "$work/cube.1" --domains "$domains" --field paper); else source=(--split "$work/domains"); fi
    start=$(date +%s.%N)
    TETISO_RSS_LOG="$work/rss-$mode.jsonl" mpirun --oversubscribe -np "$ranks" python3 "$rss" \
        "$tetiso" run "${source[@]}" --quiet -o "$work/$mode.ply" --report "$work/$mode.json"
    python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$start" "$(date +%s.%N)" >"$work/wall-$mode.txt"
done
cmp -s "$work/mesh.ply" "$work/split.ply" && same=yes || same=no
python3 - "$work" "$split_seconds" "$same" <<'PY'
import json, sys
work, split_seconds, same = sys.argv[1], float(sys.argv[2]), sys.argv[3]
print(f"tetiso split: {split_seconds:.2f} s; same surface: {same}")
for mode in ("mesh", "split"):
    r = json.load(open(f"{work}/{mode}.json"))
    peaks = sorted(json.loads(l)["peak_rss_kib"] / 1024 for l in open(f"{work}/rss-{mode}.jsonl"))
    wall = float(open(f"{work}/wall-{mode}.txt").read())
    print(f"run --{mode}: {r['tets']} tets, {r['domains']} domains, {r['triangles']} triangles; "
          f"job {r['seconds']['job']:.2f} s, wall {wall:.2f} s; rank peaks {', '.join(f'{p:.1f}' for p in peaks)} MiB")
PY
