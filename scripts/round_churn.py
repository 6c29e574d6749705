#!/usr/bin/env python3
"""How much of the surface each reduction round changes, from the report of
`tetiso reduce --report R.json` (or `tetiso extract --reduce --report`, whose
report holds the reduction under "reduction").

Every round rebuilds the fans, the edge table and the face normals of the
whole surface. An incremental update could skip only the vertices that the
previous round left alone; this prints, per round, the vertices, the
collapses and the share of surviving vertices whose fan the round changed,
then the share of all the rebuilds' vertex fans that an update could have
skipped (an upper bound on what it saves: it would still pay for its own
bookkeeping).

    scripts/round_churn.py R.json [--markdown]
"""
import argparse
import json
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("report")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()
    try:
        report = json.load(open(args.report))
    except (OSError, ValueError) as e:
        sys.exit(f"{args.report}: cannot read the report: {e}")
    reduction = report.get("reduction", report)
    rounds = reduction.get("rounds")
    if not rounds or "changed_vertices" not in rounds[0]:
        sys.exit(f"{args.report}: no per-round changed_vertices (a report of tetiso reduce, from a build that "
                 "records them, is needed)")

    rebuilt = sum(r["vertices"] for r in rounds)
    # Round r + 1 rebuilds the fans of rounds[r + 1]["vertices"] vertices, of
    # which rounds[r]["changed_vertices"] changed in round r.
    skippable = sum(nxt["vertices"] - r["changed_vertices"] for r, nxt in zip(rounds, rounds[1:]))
    if args.markdown:
        print("| round | vertices | collapses | flips | changed | changed / surviving |")
        print("|---|---|---|---|---|---|")
    for r in rounds:
        surviving = r["vertices"] - r["collapses"]
        share = 100.0 * r["changed_vertices"] / surviving if surviving else 0.0
        cells = [r["round"], r["vertices"], r["collapses"], r["flips"], r["changed_vertices"], f"{share:.1f} %"]
        text = [str(c) for c in cells]
        print(("| " + " | ".join(text) + " |") if args.markdown else "  ".join(text))
    print(f"\nvertex fans rebuilt over {len(rounds)} rounds: {rebuilt} ({rebuilt / rounds[0]['vertices']:.2f}x the input's)")
    print(f"of which unchanged since the round before: {skippable} ({100.0 * skippable / rebuilt:.1f} %)")


if __name__ == "__main__":
    main()
