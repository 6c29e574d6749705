#!/usr/bin/env bash
# How the distance bound (--max-error) sets the reduction ratio and the
# measured distance: extracts the paper surface at N (default 100) as one
# domain, reduces it at several bounds (in lattice spacings h, 0 = none) and
# checks each result against the raw surface. Writes a Markdown table with the
# command, machine and commit to OUT (default results/reduce/bound_sweep.md).
#   scripts/reduce_bound_sweep.sh [N] [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-100}
out=${2:-results/reduce/bound_sweep.md}
tetiso=${TETISO:-build/core/tetiso}
bounds=${BOUNDS:-"0.25 0.5 1 0"}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$tetiso" extract --lattice "$n" --field paper -o "$work/raw.ply"
h=$(python3 -c "print(5 / ($n - 1))")
rows=()
for k in $bounds; do
  e=$(python3 -c "print($k * $h)")
  "$tetiso" reduce "$work/raw.ply" -o "$work/r.ply" --max-error "$e" --report "$work/r.json"
  "$tetiso" check "$work/r.ply" --against "$work/raw.ply" >"$work/c.json"
  rows+=("$(python3 - "$k" "$h" "$work/r.json" "$work/c.json" <<'PY'
import json, sys
k, h = float(sys.argv[1]), float(sys.argv[2])
r, c = json.load(open(sys.argv[3])), json.load(open(sys.argv[4]))
t, a = c["topology"], c["against"]
bound = f"{k:g} h" if k > 0 else "none"
print(f"| {bound} | {r['triangles_out']:,} | {r['triangles_in'] / r['triangles_out']:.2f}x | "
      f"{a['hausdorff']['symmetric'] / h:.3f} h | {'yes' if a['same_signatures'] else 'no'} | "
      f"{t['non_manifold_edges']} | {c.get('self_intersections', 'n/a')} | {r['seconds']:.2f} |")
PY
)")
done
{
  echo "# Reduction ratio against the distance bound"
  echo
  echo "Paper surface, N = $n, one domain, $(python3 -c "import json; print(f\"{json.load(open('$work/r.json'))['triangles_in']:,}\")") triangles; \`tetiso reduce\` at Φ* = 0.9 (default), 1 thread, with \`--max-error\` set to the bound; distance = symmetric Hausdorff to the raw surface (\`tetiso check --against\`), h = lattice spacing. One run per row."
  echo
  echo "| bound | triangles out | ratio | Hausdorff | same topology | non-manifold edges | self-intersections | seconds |"
  echo "|---|---|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "- Command: \`scripts/reduce_bound_sweep.sh $n $out\`"
  echo "- Commit: \`$(git rev-parse HEAD)\`$(git diff --quiet HEAD -- core || echo ' (with uncommitted changes in core/)')"
  echo "- Machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) CPUs, $(uname -sr); $(date -u +%FT%TZ)"
} >"$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out"
