"""Reads `tetiso check OUT --against RAW` JSON and fails unless OUT is a sound
reduction of RAW: same per-component signatures, no non-manifold edges or
vertices, no degenerate triangles, consistent orientation, and a symmetric
Hausdorff distance below the bound given in lattice spacings of a
50-node lattice (h = 5/49), or as a distance with --absolute."""
import json
import sys

report = json.load(open(sys.argv[1]))
bound = float(sys.argv[2]) * (1.0 if "--absolute" in sys.argv[3:] else 5.0 / 49.0)
topology = report["topology"]
against = report["against"]
problems = []
if not against["same_signatures"]:
    problems.append("signatures differ")
for key in ("non_manifold_edges", "non_manifold_vertices", "degenerate_triangles"):
    if topology[key] != 0:
        problems.append(f"{key} = {topology[key]}")
if not topology["oriented"]:
    problems.append("not oriented")
if against["hausdorff"]["symmetric"] > bound:
    problems.append(f"hausdorff {against['hausdorff']['symmetric']} > {bound}")
if report.get("self_intersections"):
    problems.append(f"{report['self_intersections']} self-intersections")
if problems:
    sys.exit("; ".join(problems))
