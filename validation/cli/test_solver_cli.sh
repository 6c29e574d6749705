#!/usr/bin/env bash
# End-to-end checks of `--mesh` on solver files (meshes/solver/): every
# format through extract, run and split; a .pvtu's job the same bytes on 1
# and several ranks; bad files one line on stderr, exit status 2, nothing
# written. Usage: test_solver_cli.sh PATH/TO/tetiso [MPIEXEC]
set -u
tetiso=$1
mpiexec=${2:-}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
solver=$(cd "$(dirname "$0")/../../meshes/solver" && pwd)
failures=0
passed=0

# shellcheck source=cli_support.sh
source "$(dirname "$0")/cli_support.sh"
same() { # same DESCRIPTION A B
    if cmp -s "$2" "$3"; then passed=$((passed + 1)); else echo "FAIL: $1: $2 and $3 differ"; failures=$((failures + 1)); fi
}

out=$work/out
keep=$work/keep
mkdir -p "$keep"
for f in cube-ascii.vtu cube-raw-zlib.vtu cube-base64-zlib-h64.vtu cube-4.1-binary.msh cube-2.2.msh pieces.pvtu; do
    expect 0 "extract $f" -- "$tetiso" extract --mesh "$solver/$f" --array distance --level 1.5 -o "$out/s.ply"
    cp "$out/s.ply" "$keep/$f.ply"
    # cube-ascii.vtu is the reference: comparing it with itself could not fail.
    [ "$f" = cube-ascii.vtu ] || same "extract $f is extract cube-ascii.vtu" "$keep/cube-ascii.vtu.ply" "$keep/$f.ply"
done
expect 0 "run over a .msh (METIS)" -- "$tetiso" run --mesh "$solver/cube-4.1.msh" --array distance --level 1.5 --domains 3 -o "$out/m.ply"
expect 0 "run over a .pvtu, unreduced" -- "$tetiso" run --mesh "$solver/pieces.pvtu" --array distance --level 1.5 --no-reduce -o "$out/p.ply"
same "the pieces' unreduced job is the whole mesh's extraction" "$keep/cube-ascii.vtu.ply" "$out/p.ply"
expect 0 "run over a .pvtu" -- "$tetiso" run --mesh "$solver/pieces.pvtu" --array distance --level 1.5 -o "$out/p.ply" --report "$out/r.json"
cp "$out/p.ply" "$keep/one-rank.ply"
grep -q '"domains": 3' "$out/r.json" && passed=$((passed + 1)) || { echo "FAIL: the report does not give 3 domains"; failures=$((failures + 1)); }
expect 0 "the surface is a sphere" -- "$tetiso" check "$keep/one-rank.ply"
grep -q '"euler": 2' "$work/stdout" && grep -q '"closed": true' "$work/stdout" && passed=$((passed + 1)) ||
    { echo "FAIL: the .pvtu job's surface is no sphere: $(cat "$work/stdout")"; failures=$((failures + 1)); }
if [ -n "$mpiexec" ]; then
    expect 0 "run over a .pvtu on 3 ranks" -- timeout 300 "$mpiexec" --oversubscribe -np 3 "$tetiso" run --quiet \
        --mesh "$solver/pieces.pvtu" --array distance --level 1.5 -o "$out/p.ply"
    same "1 rank == 3 ranks" "$keep/one-rank.ply" "$out/p.ply"
fi
expect 0 "split of a .pvtu into its pieces" -- "$tetiso" split --mesh "$solver/pieces.pvtu" --array distance -o "$out/split"
cp -r "$out/split" "$work/split"
expect 0 "run over that split" -- "$tetiso" run --split "$work/split" --level 1.5 -o "$out/q.ply"
same "the split's job is the .pvtu's" "$keep/one-rank.ply" "$out/q.ply"

# Bad files and options: one line, status 2, nothing written.
cp "$solver"/pieces* "$work/"
head -c 3000 "$solver/cube-raw.vtu" >"$work/truncated.vtu"
expect 2 "a truncated .vtu" -- "$tetiso" extract --mesh "$work/truncated.vtu" --array distance -o "$out/s.ply"
grep -q "truncated.vtu" "$work/stderr" && passed=$((passed + 1)) || { echo "FAIL: the error does not name the file"; failures=$((failures + 1)); }
expect 2 "a missing array" -- "$tetiso" run --mesh "$solver/pieces.pvtu" --array pressure -o "$out/s.ply"
expect 2 "an attribute of a .vtu" -- "$tetiso" extract --mesh "$solver/cube-ascii.vtu" --attribute 0 -o "$out/s.ply"
expect 2 "wrong node ids" -- "$tetiso" run --mesh "$solver/pieces.pvtu" --array distance --node-ids distance -o "$out/s.ply"
expect 2 "a .pvtu with another domain count" -- "$tetiso" run --mesh "$solver/pieces.pvtu" --array distance --domains 2 -o "$out/s.ply"
rm "$work/pieces_1.vtu"
expect 2 "a piece missing" -- "$tetiso" run --mesh "$work/pieces.pvtu" --array distance -o "$out/s.ply"
grep -q "pieces_1.vtu" "$work/stderr" && passed=$((passed + 1)) || { echo "FAIL: the error does not name the missing piece"; failures=$((failures + 1)); }
if [ -n "$mpiexec" ]; then
    # mpirun adds its own lines; the job's own is the one that names the piece.
    rm -rf "$out" && mkdir -p "$out"
    timeout 300 "$mpiexec" --oversubscribe -np 2 "$tetiso" run --quiet --mesh "$work/pieces.pvtu" --array distance \
        -o "$out/s.ply" >"$work/stdout" 2>"$work/stderr"
    status=$?
    if [ "$status" -eq 2 ] && grep -q "^tetiso: .*pieces_1.vtu: cannot open" "$work/stderr" && [ -z "$(ls -A "$out")" ]; then
        passed=$((passed + 1))
    else
        echo "FAIL: a piece missing, 2 ranks: status $status: $(cat "$work/stderr")"
        failures=$((failures + 1))
    fi
fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
