#!/usr/bin/env python3
"""Turns the reduction benchmark's output into results/reduce/README.md.

Reads, from the directory given (default results/reduce):
  bench_reduce.json  Google Benchmark JSON (aggregates of repetitions, with
                     the quality counters of bench/bench_reduce.cpp)
  meta.json          command, machine and commit, written by bench_reduce.sh
and writes README.md there. Python standard library only.
"""
import json
import sys
from pathlib import Path

from bench_report_common import command_section, load_aggregates, table

TARGET_N = 100           # the lattice the targets below are stated for
TARGET_REDUCTION = 10.0  # raw triangles over tetiso's, paper field, default Φ*
TARGET_SPEED = 1.0       # tetiso single-thread input rate over meshoptimizer's, same triangle count

# Cases with their own repetition count carry "/repeats:K" in their names.
NAME = (r"^reduce/(?P<method>tetiso|meshopt|cgal|openmesh)/N:(?P<n>\d+)/threads:(?P<threads>\d+)"
        r"(/repeats:\d+)?(/real_time)?$")
METHOD_ORDER = {"tetiso": 0, "meshopt": 1, "cgal": 2, "openmesh": 3}
METHOD_TITLE = {"tetiso": "tetiso reduce", "meshopt": "meshopt_simplify",
                "cgal": "CGAL edge_collapse (Garland–Heckbert)", "openmesh": "OpenMesh Decimater (quadric)"}
CAREFUL = ("cgal", "openmesh")  # the baselines that keep topology


def load_cases(path):
    """Per (method, n, threads): median seconds, fastest seconds, cv and the counters."""
    context, aggregates = load_aggregates(path, NAME, lambda m: (m["method"], int(m["n"]), int(m["threads"])))
    cases = {}
    for key, aggregate in aggregates.items():
        row = aggregate["median"]
        case = {name: row[name] for name in row if isinstance(row[name], (int, float))}
        case["seconds"] = aggregate["time_ms"] / 1e3
        case["min_seconds"] = aggregate.get("min_ms", float("nan")) / 1e3
        case["cv"] = aggregate.get("cv")
        case["repetitions"] = row.get("repetitions")
        # Input rate from the median time, so that the table's seconds and
        # rates agree (a median of rates need not be the rate of the median).
        case["rate"] = row["triangles_in"] / case["seconds"]
        cases[key] = case
    return context, cases


def ordered(cases, n):
    return sorted((key for key in cases if key[1] == n), key=lambda k: (METHOD_ORDER[k[0]], k[2]))


def topology_kept(case):
    return (case["same_topology"] == 1 and case["non_manifold_edges"] == 0
            and case["non_manifold_vertices"] == 0 and case["misoriented_edges"] == 0)


def crossings(case):
    if "self_intersections" in case:
        return f"{int(case['self_intersections']):,}"
    if case["non_manifold_edges"] or case["non_manifold_vertices"]:
        return "not measured (non-manifold: CGAL cannot take it)"
    return "not measured"


def figures_section(cases, n):
    rows = []
    for key in ordered(cases, n):
        method, _, threads = key
        c = cases[key]
        rows.append([METHOD_TITLE[method], threads, c["repetitions"] or "—", f"{int(c['triangles_in']):,}", f"{int(c['triangles_out']):,}",
                     f"{c['triangles_in'] / c['triangles_out']:.2f}×", f"**{c['seconds']:.3f}**",
                     f"{c['min_seconds']:.3f}", f"{100 * c['cv']:.1f} %" if c["cv"] is not None else "—",
                     f"**{c['rate'] / 1e6:.2f}**", f"{c['hausdorff']:.5f}", f"{c['hausdorff_h']:.3f}",
                     "yes" if c["same_topology"] == 1 else "**no**",
                     f"{int(c['non_manifold_edges'])} / {int(c['non_manifold_vertices'])}",
                     f"{int(c['misoriented_edges'])}",
                     f"{int(c['degenerate_triangles'])} / {int(c['near_degenerate_triangles'])}", crossings(c)])
    header = ["method", "threads", "runs", "triangles in", "triangles out", "ratio", "median s", "fastest s", "cv",
              "Mtris/s input", "Hausdorff", "Hausdorff / h", "same topology", "non-manifold edges / vertices",
              "misoriented edges", "degenerate / near-degenerate", "self-intersections"]
    return [table(header, rows), ""]


def targets_section(cases, n):
    t1, mo = cases.get(("tetiso", n, 1)), cases.get(("meshopt", n, 1))
    tetiso_keys = [key for key in ordered(cases, n) if key[0] == "tetiso"]
    lines = []
    if t1 and mo:
        speed = t1["rate"] / mo["rate"]
        met = speed >= TARGET_SPEED
        lines.append(f"- **Speed**, tetiso single-thread at least as fast as meshoptimizer to the same triangle "
                     f"count: **{'met' if met else 'missed'}**. Median {t1['seconds']:.3f} s "
                     f"({t1['rate'] / 1e6:.2f} M input triangles/s) against {mo['seconds']:.3f} s "
                     f"({mo['rate'] / 1e6:.2f} M/s): tetiso runs at {speed:.2f}× meshoptimizer's rate "
                     f"(fastest repetitions: {mo['min_seconds'] / t1['min_seconds']:.2f}×).")
        for key in tetiso_keys:
            if key[2] != 1:
                c = cases[key]
                lines.append(f"  With {key[2]} threads tetiso takes {c['seconds']:.3f} s "
                             f"({c['rate'] / 1e6:.2f} M/s, {t1['seconds'] / c['seconds']:.2f}× its single-thread "
                             "speed).")
    if t1:
        ratio = t1["triangles_in"] / t1["triangles_out"]
        lines.append(f"- **Reduction**, default Φ* gives ≥ {TARGET_REDUCTION:g}× fewer triangles than raw: "
                     f"**{'met' if ratio >= TARGET_REDUCTION else 'missed'}**, {int(t1['triangles_in']):,} → "
                     f"{int(t1['triangles_out']):,} triangles ({ratio:.2f}×).")
    if tetiso_keys:
        kept = all(topology_kept(cases[key]) for key in tetiso_keys)
        lines.append(f"- **Topology kept** by tetiso (same per-component genus, boundary loops and orientability "
                     f"as the raw surface; no non-manifold edge or vertex; no misoriented edge): "
                     f"**{'met' if kept else 'missed'}** in "
                     + ", ".join(f"{key[2]}-thread" for key in tetiso_keys) + " output.")
        measured = [cases[key] for key in tetiso_keys if "self_intersections" in cases[key]]
        if len(measured) == len(tetiso_keys):
            total = sum(int(c["self_intersections"]) for c in measured)
            lines.append(f"- **Zero self-intersections** in tetiso's output (CGAL, exact predicates): "
                         f"**{'met' if total == 0 else 'missed'}**, "
                         + ", ".join(f"{int(cases[key]['self_intersections'])} with {key[2]} thread(s)"
                                     for key in tetiso_keys) + ".")
        else:
            lines.append("- **Zero self-intersections**: not assessed, the count was not measured "
                         "(no CGAL in this build, or an output CGAL cannot take).")
    for method in CAREFUL:
        c = cases.get((method, n, 1))
        if not (c and t1):
            continue
        against_meshopt = f", {c['rate'] / mo['rate']:.3f}× meshoptimizer's rate" if mo else ""
        lines.append(f"- {METHOD_TITLE[method]}, for comparison: {c['seconds']:.3f} s "
                     f"({c['rate'] / 1e6:.2f} M input triangles/s{against_meshopt}); tetiso single-thread is "
                     f"**{c['seconds'] / t1['seconds']:.2f}× as fast**. Topology "
                     f"{'kept' if topology_kept(c) else '**not kept**'}, self-intersections {crossings(c)}, "
                     f"Hausdorff {c['hausdorff_h']:.3f} h (tetiso's {t1['hausdorff_h']:.3f} h).")
    if mo:
        kept = topology_kept(mo)
        lines.append(f"- meshoptimizer, for comparison: topology {'kept' if kept else '**not kept**'} "
                     f"(same signatures: {'yes' if mo['same_topology'] == 1 else 'no'}, non-manifold edges "
                     f"{int(mo['non_manifold_edges'])}, vertices {int(mo['non_manifold_vertices'])}), "
                     f"self-intersections {crossings(mo)}, Hausdorff {mo['hausdorff_h']:.3f} h.")
    lines.append("")
    return lines


def sanity_section(cases, n):
    tetiso_out = {int(cases[key]["triangles_out"]) for key in ordered(cases, n) if key[0] == "tetiso"}
    lines = []
    if len(tetiso_out) > 1:
        lines.append("**Sanity check failed:** tetiso's triangle counts differ between thread counts: "
                     + ", ".join(f"{count:,}" for count in sorted(tetiso_out)) + ".")
    elif tetiso_out:
        lines.append(f"Sanity check: every tetiso case produced the same {next(iter(tetiso_out)):,} triangles "
                     "(the output does not depend on the thread count).")
    mo = cases.get(("meshopt", n, 1))
    if mo and tetiso_out:
        target = max(tetiso_out)
        out = int(mo["triangles_out"])
        relation = "exactly that count" if out == target else f"{out:,}, {target - out:,} fewer"
        lines.append(f"meshopt_simplify was asked for at most {target:,} triangles and produced {relation}.")
    for method in CAREFUL:
        c = cases.get((method, n, 1))
        if c and tetiso_out:
            target = max(tetiso_out)
            out = int(c["triangles_out"])
            relation = "exactly that count" if out == target else f"{out:,}, {target - out:,} fewer"
            lines.append(f"{METHOD_TITLE[method]} was asked for at most {target:,} triangles and produced "
                         f"{relation}.")
    lines.append("")
    return lines


def raw_section(context, n):
    prefix = f"raw/N:{n}/"
    raw = {key[len(prefix):]: value for key, value in context.items() if key.startswith(prefix)}
    if not raw:
        return []
    spacing = float(raw["spacing"])
    return [f"The raw surface at N = {n}: {int(raw['triangles']):,} triangles, {int(raw['vertices']):,} vertices, "
            f"{raw['components']} component{'s' if raw['components'] != '1' else ''}; non-manifold edges {raw['non_manifold_edges']}, vertices "
            f"{raw['non_manifold_vertices']}; degenerate triangles {raw['degenerate_triangles']}, near-degenerate "
            f"(< 1°) {raw['near_degenerate_triangles']}; self-intersections {raw['self_intersections']}. "
            f"Lattice spacing h = {spacing:.6f}; tetiso's max_error = {float(raw['max_error']):.6f} "
            f"({float(raw['max_error']) / spacing:.2f} h).", ""]


def main():
    directory = Path(sys.argv[1] if len(sys.argv) > 1 else "results/reduce")
    context, cases = load_cases(directory / "bench_reduce.json")
    meta = json.loads((directory / "meta.json").read_text()) if (directory / "meta.json").exists() else {}
    sizes = sorted({n for (_, n, _) in cases})

    out = ["# Reduction: tetiso vs meshoptimizer, CGAL and OpenMesh", ""]
    out += ["The paper's test surface: the N×N×N lattice on [0,5]³ as one domain (D = 1), field "
            "2cos(10x)+2sin(10y)+cos(10z) at its default level "
            f"{float(context.get('level', 0.5)):g}, extracted by marching tetrahedra and merged by key as "
            "`tetiso extract` does. tetiso's `reduce` (default `ReduceOptions`, Φ* = "
            f"{float(context.get('phi', 0.9)):g}, except `max_error` = "
            f"{float(context.get('max_error_spacings', 0.25)):g} h as `tetiso run` sets it) and meshoptimizer's "
            "`meshopt_simplify` to the triangle count tetiso reached run in the same process on the same "
            "surface. Only the simplification call is timed (real time); quality is measured once per case "
            "on that case's own output, outside the timed loop.", ""]
    for n in sizes:
        out += [f"## N = {n}", ""]
        out += raw_section(context, n)
        out += ["Medians of the repetitions. Mtris/s input = input triangles / median seconds; ratio = "
                "triangles in / triangles out; Hausdorff = symmetric Hausdorff distance to the raw surface "
                "(sampled, `tetiso::hausdorff`), absolute and in lattice spacings h; same topology = the same "
                "sorted list of per-component (genus, boundary loops, orientable) signatures as the raw "
                "surface; degenerate = collapsed or zero-area, near-degenerate = smallest angle below 1°.", ""]
        out += figures_section(cases, n)
        out += ["### Targets", ""]
        if n != TARGET_N:
            out += [f"The targets are stated for N = {TARGET_N}; at N = {n} these lines are for context.", ""]
        out += targets_section(cases, n)
        out += sanity_section(cases, n)

    out += ["## How they were run", "",
            "- tetiso: `tetiso::reduce(raw, options)` with `ReduceOptions{}` except `max_error` = "
            "`JobConfig{}.max_error_spacings` × h and `threads`; the call includes its input checks and the "
            "final compaction.",
            "- meshoptimizer: `tetiso::reference::meshopt_simplify(raw, T, 1.0f)`, T = tetiso's output "
            "triangle count, error unbounded so that it stops at the count, borders not locked (the surface "
            "is open at the cube's faces). The call includes the adapter's copy into interleaved positions and "
            "32-bit indices and its compaction back to a Piece; meshoptimizer itself is serial.",
            "- CGAL: `tetiso::reference::cgal_simplify(raw, T)`: a `CGAL::Surface_mesh` (double coordinates) "
            "built from the piece, `Surface_mesh_simplification::edge_collapse` with "
            "`GarlandHeckbert_plane_policies` (quadric cost, the quadric's optimal position for the survivor), "
            "stopped once the mesh has at most T faces, and the survivors copied back.",
            "- OpenMesh: `tetiso::reference::openmesh_decimate(raw, T)`: a `TriMesh_ArrayKernelT` built from "
            "the piece, `DecimaterT` with `ModQuadricT` (error unbounded), `decimate_to_faces(0, T)`, and the "
            "survivors copied back. Its collapses are halfedge collapses: survivors keep their positions.",
            "- Both careful baselines include building their halfedge mesh and copying back in the timed call, "
            "as meshoptimizer's includes its adapter; they take tens of seconds per run, so they run fewer "
            "repetitions (the table's runs).",
            "- Each timed iteration frees the previous output. Building the surface, the checks and one "
            "untimed tetiso reduction that fixes T happen before timing.",
            "- Self-intersections: `tetiso::count_self_intersections` (CGAL Polygon Mesh Processing); it "
            "answers only for meshes CGAL can take as a halfedge mesh without splitting vertices, so a "
            "non-manifold output is reported as not measured, and its non-manifold counts say why.", ""]

    out += command_section(meta, context, "scripts/report_reduce.py results/reduce")
    (directory / "README.md").write_text("\n".join(out))


if __name__ == "__main__":
    main()
