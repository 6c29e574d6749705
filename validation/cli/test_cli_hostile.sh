#!/usr/bin/env bash
# What a hostile but realistic user tries against the `tetiso` command (issue
# 43's probe): outputs that name inputs or each other, inputs that are not
# regular files, signals during a write, numbers in odd notations, and
# options that mean nothing together. Each case is one row of README's
# "Bad input" table. Usage: test_cli_hostile.sh PATH/TO/tetiso
set -u
tetiso=$(realpath "$1")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
passed=0
meshes=$(cd "$(dirname "$0")/../../meshes" && pwd)

# shellcheck source=cli_support.sh
source "$(dirname "$0")/cli_support.sh"
out=$work/out

# says TEXT: the last command's stderr holds TEXT (a fixed string).
says() {
    grep -qF -- "$1" "$work/stderr" && passed=$((passed + 1)) ||
        { echo "FAIL: stderr lacks '$1': $(cat "$work/stderr")"; failures=$((failures + 1)); }
}
# unchanged FILE SUM: FILE still has the checksum SUM.
unchanged() {
    [ "$(cksum <"$1")" = "$2" ] && passed=$((passed + 1)) ||
        { echo "FAIL: $1 was changed"; failures=$((failures + 1)); }
}

# An output that is another output or an input: refused before any work,
# the file left as it was, through ./, a symbolic link and a hard link too.
"$tetiso" extract --lattice 12 --field sphere -o "$work/keep.ply"
sum=$(cksum <"$work/keep.ply")
expect 2 "report over the surface" -- "$tetiso" extract --lattice 12 -o "$out/same.ply" --report "$out/same.ply"
says "it is the same file as the output"
expect 2 "report over the surface through ./" -- bash -c 'cd "$1" && exec "$2" extract --lattice 12 -o same.ply --report ./same.ply' - "$out" "$tetiso"
ln -s "$work/keep.ply" "$work/link.ply"
ln "$work/keep.ply" "$work/hard.ply"
for report in "$work/keep.ply" "$work/../$(basename "$work")/keep.ply" "$work/link.ply" "$work/hard.ply"; do
    expect 2 "reduce's report over its input ($report)" -- "$tetiso" reduce "$work/keep.ply" -o "$out/r.ply" --report "$report"
    says "it is the same file as the input"
    unchanged "$work/keep.ply" "$sum"
done
expect 2 "reduce's surface over its input" -- "$tetiso" reduce "$work/link.ply" -o "$work/keep.ply"
unchanged "$work/keep.ply" "$sum"
ln -s "$work/keep2.ply" "$work/keep2link.ply"
expect 2 "reduce's surface and report one file through a link" -- "$tetiso" reduce "$work/keep.ply" -o "$work/keep2.ply" --report "$work/keep2link.ply"
cp "$meshes/cube.1.node" "$work/cube.1.node" && cp "$meshes/cube.1.ele" "$work/cube.1.ele"
node_sum=$(cksum <"$work/cube.1.node")
expect 2 "extract's report over a TetGen mesh's .node" -- "$tetiso" extract --mesh "$work/cube.1" -o "$out/t.ply" --report "$work/cube.1.node"
unchanged "$work/cube.1.node" "$node_sum"
expect 2 "run's report over its partition file" -- "$tetiso" run --mesh "$work/cube.1" --domains 2 --partition "$work/cube.1.node" -o "$out/t.ply" --report "$work/cube.1.node"
unchanged "$work/cube.1.node" "$node_sum"

# Inputs that are not regular files: refused, never read (a device has no
# end, a pipe may never open). Under a memory and time limit, so that a
# reader that does read them fails here rather than eats the machine.
limited() { bash -c 'ulimit -v 1500000; exec timeout 20 "$@"' - "$@"; }
ln -s /dev/zero "$work/zero.ply"
ln -s /dev/zero "$work/zero.vtu"
ln -s /dev/zero "$work/zero.msh"
ln -s /dev/zero "$work/zero.node" && cp "$meshes/cube.1.ele" "$work/zero.ele"
mkfifo "$work/fifo.vtu" "$work/fifo.part"
sed 's|Source="pieces_1.vtu"|Source="/dev/zero"|' "$meshes/solver/pieces.pvtu" >"$work/zero.pvtu"
cp "$meshes"/solver/pieces_*.vtu "$work/"
for input in "check $work/zero.ply" "reduce $work/zero.ply -o $out/r.ply" "extract --mesh $work/zero.vtu -o $out/t.ply" \
    "extract --mesh $work/zero.msh -o $out/t.ply" "extract --mesh $work/zero -o $out/t.ply" \
    "extract --mesh $work/fifo.vtu -o $out/t.ply" "extract --mesh $work/zero.pvtu --array distance -o $out/t.ply" \
    "run --mesh $work/zero.pvtu --array distance --quiet -o $out/t.ply" \
    "split --mesh $work/zero.pvtu --array distance -o $out/s" \
    "run --mesh $meshes/cube.1 --partition $work/fifo.part --quiet -o $out/t.ply"; do
    # shellcheck disable=SC2086 # the case is several arguments
    expect 2 "not a regular file: $input" -- limited "$tetiso" $input
    says "not a regular file"
done
"$tetiso" split --mesh "$meshes/cube.1" --field sphere --domains 2 --quiet -o "$work/split2"
rm "$work/split2/domain-1.tetiso" && ln -s /dev/zero "$work/split2/domain-1.tetiso"
expect 2 "a split file that is a link to /dev/zero" -- limited "$tetiso" run --split "$work/split2" --quiet -o "$out/t.ply"
says "domain-1.tetiso: not a regular file"

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
