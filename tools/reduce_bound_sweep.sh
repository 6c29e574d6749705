#!/usr/bin/env bash
# How the distance bound (--max-error) sets the reduction ratio and the
# measured distance: extracts each field's surface at N (default 100) as one
# domain, reduces it at several bounds (in lattice spacings h, 0 = none) and
# checks each result against the raw surface: the symmetric Hausdorff distance
# (sampled over the triangles) and the largest distance of the raw surface's
# vertices, the quantity the bound is on. Writes a Markdown table with the
# command, machine and commit to OUT (default results/reduce/bound_sweep.md).
#   tools/reduce_bound_sweep.sh [N] [OUT]
# Environment: FIELDS (default "paper sphere torus gyroid"), BOUNDS (default
# "0.1 0.25 0.5 0"), TETISO (default build/core/tetiso).
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-100}
out=${2:-results/reduce/bound_sweep.md}
tetiso=${TETISO:-build/core/tetiso}
bounds=${BOUNDS:-"0.1 0.25 0.5 0"}
fields=${FIELDS:-"paper sphere torus gyroid"}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
h=$(python3 -c "print(5 / ($n - 1))")
rows=()
for field in $fields; do
  "$tetiso" extract --lattice "$n" --field "$field" -o "$work/raw.ply"
  for k in $bounds; do
    e=$(python3 -c "print($k * $h)")
    "$tetiso" reduce "$work/raw.ply" -o "$work/r.ply" --max-error "$e" --report "$work/r.json"
    "$tetiso" check "$work/r.ply" --against "$work/raw.ply" >"$work/c.json"
    "$tetiso" check "$work/raw.ply" --against "$work/r.ply" --vertices-only >"$work/v.json"
    rows+=("$(python3 - "$field" "$k" "$h" "$work/r.json" "$work/c.json" "$work/v.json" <<'PY'
import json, sys
field, k, h = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
r, c, v = (json.load(open(p)) for p in sys.argv[4:7])
t, a = c["topology"], c["against"]
bound = f"{k:g} h" if k > 0 else "none"
hd = a["hausdorff"]["symmetric"] / h
over = f"{hd / k:.2f}" if k > 0 else "–"
print(f"| {field} | {bound} | {r['triangles_in']:,} | {r['triangles_out']:,} | "
      f"{r['triangles_in'] / r['triangles_out']:.2f}x | {v['against']['hausdorff']['forward'] / h:.3f} h | "
      f"{hd:.3f} h | {over} | {'yes' if a['same_signatures'] else 'no'} | "
      f"{t['non_manifold_edges']} | {c.get('self_intersections', 'n/a')} | {r['seconds']:.2f} |")
PY
)")
  done
done
{
  echo "# Reduction ratio against the distance bound"
  echo
  echo "Built-in fields at N = $n, one domain; \`tetiso reduce\` at Φ* = 0.9 (default), 1 thread, with \`--max-error\` set to the bound. \"vertices\": the largest distance of the raw surface's vertices to the result (\`tetiso check RAW --against OUT --vertices-only\`, forward), the quantity the bound is on; \"Hausdorff\": the symmetric distance sampled over both surfaces' triangles (\`tetiso check --against\`); \"over\": Hausdorff / bound. h = lattice spacing. One run per row."
  echo
  echo "| field | bound | triangles in | triangles out | ratio | vertices | Hausdorff | over | same topology | non-manifold edges | self-intersections | seconds |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "- Command: \`tools/reduce_bound_sweep.sh $n $out\`"
  echo "- Commit: \`$(git rev-parse HEAD)\`$(git diff --quiet HEAD -- core || echo ' (with uncommitted changes in core/)')"
  echo "- Machine: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) CPUs, $(uname -sr); $(date -u +%FT%TZ)"
} >"$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out"
