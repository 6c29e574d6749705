#!/usr/bin/env bash
# `tetiso check --strict` as a gate in a user's pipeline: exit 0 for a clean
# surface, 1 with one line per violated clause of the surface contract (each
# "tetiso check: FILE: CLAUSE: ..."), 2 for bad input as every command; the
# JSON names where each defect is. Usage: test_check_cli.sh PATH/TO/tetiso
set -u
tetiso=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
passed=0

# shellcheck source=cli_support.sh
source "$(dirname "$0")/cli_support.sh"

# ok DESCRIPTION COMMAND...: passes when the command succeeds.
ok() {
    local what=$1
    shift
    if "$@"; then passed=$((passed + 1)); else echo "FAIL: $what"; failures=$((failures + 1)); fi
}

# An ASCII PLY of the given vertex lines and triangle lines.
ply() {
    local file=$1 vertices=$2 faces=$3
    {
        echo "ply"; echo "format ascii 1.0"
        echo "element vertex $(grep -c . <<<"$vertices")"
        echo "property float x"; echo "property float y"; echo "property float z"
        echo "element face $(grep -c . <<<"$faces")"
        echo "property list uchar int vertex_indices"; echo "end_header"
        echo "$vertices"; sed 's/^/3 /' <<<"$faces"
    } >"$file"
}

tetrahedron_vertices=$'0 0 0\n1 0 0\n0 1 0\n0 0 1'
tetrahedron_faces=$'0 2 1\n0 1 3\n0 3 2\n1 2 3'
ply "$work/tetrahedron.ply" "$tetrahedron_vertices" "$tetrahedron_faces"
expect 0 "a clean surface passes" -- "$tetiso" check --strict "$work/tetrahedron.ply"
ok "a clean surface has no violation in the JSON" python3 -c \
    "import json,sys; assert json.load(open(sys.argv[1]))['violations'] == []" "$work/stdout"

# A flipped face, a second vertex at a corner's position (unreferenced, so
# that it crosses nothing) and a zero-area triangle apart: three clauses,
# three lines.
ply "$work/broken.ply" "$tetrahedron_vertices"$'\n0 0 0\n3 3 3\n4 3 3\n5 3 3' $'0 2 1\n0 1 3\n0 3 2\n1 3 2\n5 6 7'
"$tetiso" check --strict "$work/broken.ply" >"$work/stdout" 2>"$work/stderr"
ok "a broken surface exits 1" [ $? -eq 1 ]
ok "one line per violated clause" [ "$(wc -l <"$work/stderr")" -eq 3 ]
for clause in "degenerate triangles: 1 (0 collapsed, 1 of zero area); the first is triangle 4" \
    "duplicate positions: 1 vertex repeats the position of another; the first is vertices 0, 4 at (0, 0, 0)" \
    "orientation: 3 edges are run the same way by both their triangles; the first is edge 1, 2"; do
    ok "the line '$clause'" grep -qF "tetiso check: $work/broken.ply: $clause" "$work/stderr"
done
ok "the JSON names the repeated position and the lines" python3 - "$work/stdout" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
assert report["topology"]["where"]["duplicate_positions"] == [{"vertices": [0, 4], "at": [0.0, 0.0, 0.0]}], report
assert len(report["violations"]) == 3
PY
# Without --strict the same surface is only reported on.
expect 0 "without --strict a broken surface is reported, not failed" -- "$tetiso" check "$work/broken.ply"

# Two triangles through each other (CGAL builds: the JSON says null otherwise).
ply "$work/crossing.ply" $'0 0 0\n2 0 0\n0 2 0\n0.5 0.5 -1\n0.5 0.5 1\n3 3 0.5' $'0 1 2\n3 4 5'
"$tetiso" check --strict "$work/crossing.ply" >"$work/stdout" 2>"$work/stderr"
status=$?
if python3 -c "import json,sys; sys.exit(json.load(open(sys.argv[1]))['self_intersections'] is None)" \
    "$work/stdout" 2>/dev/null; then
    ok "crossing triangles exit 1" [ $status -eq 1 ]
    ok "the crossing pair's line" grep -qF "self-intersections: 1 pair of triangles cross; the first is triangles 0 and 1" \
        "$work/stderr"
    ok "the JSON names the crossing pair" python3 -c \
        "import json,sys; assert json.load(open(sys.argv[1]))['topology']['where']['self_intersections'][0]['triangles'] == [0, 1]" \
        "$work/stdout"
    expect 0 "--no-self-intersections gates without them" -- "$tetiso" check --strict --no-self-intersections \
        "$work/crossing.ply"
else
    ok "without CGAL a gate that would skip self-intersections says so" grep -q "built without CGAL" "$work/stderr"
fi

# --against: the component signatures must be the reference's.
"$tetiso" extract --lattice 16 --field sphere -o "$work/sphere.ply"
"$tetiso" extract --lattice 16 --field torus -o "$work/torus.ply"
"$tetiso" run --lattice 16 --domains 4 --field torus --quiet -o "$work/torus-reduced.ply"
expect 0 "a reduced torus against its raw surface" -- "$tetiso" check --strict "$work/torus-reduced.ply" --against "$work/torus.ply"
"$tetiso" check --strict "$work/sphere.ply" --against "$work/torus.ply" >"$work/stdout" 2>"$work/stderr"
ok "a sphere against a torus exits 1" [ $? -eq 1 ]
ok "the signatures' line" grep -qF "signatures: the components are 1 × (genus 0, 0 boundary loops), the reference's 1 × (genus 1, 0 boundary loops)" \
    "$work/stderr"

# A surface through a whole layer of lattice nodes (every crossing at its
# node) is clean as extracted, raw and reduced.
"$tetiso" extract --lattice 5 --field x --level 2.5 -o "$work/plane.ply"
expect 0 "a plane through lattice nodes, raw" -- "$tetiso" check --strict "$work/plane.ply"
"$tetiso" run --lattice 5 --domains 8 --field x --level 2.5 --seam-rings 0 --quiet -o "$work/plane-reduced.ply"
expect 0 "a plane through lattice nodes, reduced" -- "$tetiso" check --strict "$work/plane-reduced.ply"

# Bad input is still status 2 with one line.
expect 2 "--strict of a missing file" -- "$tetiso" check --strict "$work/nothing.ply"
expect 2 "--strict against a missing file" -- "$tetiso" check --strict "$work/sphere.ply" --against "$work/nothing.ply"

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
