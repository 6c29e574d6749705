#!/usr/bin/env bash
# End-to-end checks of the `tetiso` command: what a user sees for good and
# bad arguments. Usage: test_cli.sh PATH/TO/tetiso
set -u
tetiso=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
passed=0

# shellcheck source=cli_support.sh
source "$(dirname "$0")/cli_support.sh"

out=$work/out
expect 0 "help" -- "$tetiso" --help
expect 0 "extract help" -- "$tetiso" extract --help
expect 0 "extract writes a vtp" -- "$tetiso" extract --lattice 12 --domains 3 --field sphere -o "$out/s.vtp" --report "$out/r.json"
expect 2 "no subcommand" -- "$tetiso"
expect 2 "unknown flag" -- "$tetiso" extract --lattice 10 --bogus -o "$out/s.ply"
expect 2 "unknown field" -- "$tetiso" extract --lattice 10 --field "sphere(" -o "$out/s.ply"
expect 2 "expression with an unknown variable" -- "$tetiso" extract --lattice 10 --field "x+w" -o "$out/s.ply"
expect 2 "N < 2" -- "$tetiso" extract --lattice 1 -o "$out/s.ply"
expect 2 "D < 1" -- "$tetiso" extract --lattice 10 --domains 0 -o "$out/s.ply"
expect 2 "more domains than cells" -- "$tetiso" extract --lattice 3 --domains 9 -o "$out/s.ply"
 # Every command takes the same range of thread counts; far above it libgomp
# overflowed its stack (SIGSEGV, nothing said) or could not create them.
for command in "extract --lattice 20" "run --lattice 20 --domains 2 --quiet"; do
    for threads in 100000 50000 -1 1.5; do
        # shellcheck disable=SC2086 # the command is several arguments
        expect 2 "$command --threads $threads" -- "$tetiso" $command --threads "$threads" -o "$out/s.ply"
    done
done
"$tetiso" extract --lattice 12 --field sphere -o "$work/small.ply"
expect 2 "reduce --threads 100000" -- "$tetiso" reduce "$work/small.ply" --threads 100000 -o "$out/r.ply"
grep -q -- "--threads: 100000 is outside 0 (all cores) to 1024" "$work/stderr" && passed=$((passed + 1)) ||
    { echo "FAIL: a thread count's error does not give the range: $(cat "$work/stderr")"; failures=$((failures + 1)); }
# One check per kind of option, the same in every command: a NaN bound is no
# bound at all (run took it as "none"), a level must fit a float (and be
# called finite when it is), a domain count says so without a 300-digit range.
for bound in nan inf -inf -1; do
    expect 2 "extract --max-error $bound" -- "$tetiso" extract --lattice 10 --reduce --max-error "$bound" -o "$out/s.ply"
    expect 2 "run --max-error $bound" -- "$tetiso" run --lattice 10 --domains 2 --max-error "$bound" -o "$out/s.ply"
    expect 2 "reduce --max-error $bound" -- "$tetiso" reduce "$work/small.ply" --max-error "$bound" -o "$out/r.ply"
done
for command in "extract --lattice 10" "run --lattice 10 --domains 2"; do
    # shellcheck disable=SC2086
    expect 2 "$command --level 1e39" -- "$tetiso" $command --level 1e39 -o "$out/s.ply"
    grep -q "1e39 does not fit a float" "$work/stderr" && passed=$((passed + 1)) ||
        { echo "FAIL: $command: a level too large for a float: $(cat "$work/stderr")"; failures=$((failures + 1)); }
    # shellcheck disable=SC2086
    expect 2 "$command --level nan" -- "$tetiso" $command --level nan -o "$out/s.ply"
done
for command in "extract --lattice 10" "run --lattice 10" "split --mesh meshes/cube.1"; do
    # shellcheck disable=SC2086
    expect 2 "$command --domains 0" -- "$tetiso" $command --domains 0 -o "$out/s.ply"
    grep -q -- "--domains: must be at least 1, not 0" "$work/stderr" && [ "$(wc -c <"$work/stderr")" -lt 100 ] &&
        passed=$((passed + 1)) ||
        { echo "FAIL: $command: --domains 0's error: $(cat "$work/stderr")"; failures=$((failures + 1)); }
done
expect 2 "unwritable output directory" -- "$tetiso" extract --lattice 10 -o "$out/missing/s.ply"
expect 2 "unknown output format" -- "$tetiso" extract --lattice 10 -o "$out/s.stl"
expect 2 "check of a missing file" -- "$tetiso" check "$out/nothing.ply"
# A directory opens for reading on Linux and fails only when read (an
# internal error before; asked for its size, it answers 2^63 - 1): it must be
# a plain error naming it.
mkdir -p "$work/folder.ply" "$work/folder.vtp"
expect 2 "check of a directory" -- "$tetiso" check "$work/folder.ply"
grep -q "folder.ply: is a directory" "$work/stderr" && passed=$((passed + 1)) ||
    { echo "FAIL: a directory's error does not say so: $(cat "$work/stderr")"; failures=$((failures + 1)); }
expect 2 "reduce of a directory" -- "$tetiso" reduce "$work/folder.vtp" -o "$out/r.ply"
mkdir -p "$work/folder.node"
expect 2 "mesh whose .node is a directory" -- "$tetiso" extract --mesh "$work/folder" -o "$out/t.ply"
meshes=$(cd "$(dirname "$0")/../../meshes" && pwd)
expect 0 "extract from a TetGen mesh" -- "$tetiso" extract --mesh "$meshes/cube.1" --field torus --reduce -o "$out/t.vtp"
expect 2 "unknown device" -- "$tetiso" extract --lattice 10 --device tpu -o "$out/s.ply"
# --device gpu: where there is no GPU (CI) a one-line error that says so and no
# file; where there is one, the same bytes as the CPU's, for the lattice in
# domains and for the unstructured mesh.
if "$tetiso" extract --lattice 8 --device gpu -o "$work/probe.ply" 2>"$work/probe.err"; then
    for source in "--lattice 40 --domains 8 --field gyroid" "--mesh $meshes/cube.1 --field sphere"; do
        # shellcheck disable=SC2086 # the source is several arguments
        "$tetiso" extract $source -o "$work/cpu.ply" && "$tetiso" extract $source --device gpu -o "$work/gpu.ply" &&
            cmp -s "$work/cpu.ply" "$work/gpu.ply" && passed=$((passed + 1)) ||
            { echo "FAIL: --device gpu differs from the CPU for $source"; failures=$((failures + 1)); }
    done
else
    expect 2 "--device gpu without a GPU" -- "$tetiso" extract --lattice 10 --device gpu -o "$out/s.ply"
    grep -q "^tetiso: --device gpu: " "$work/stderr" && passed=$((passed + 1)) ||
        { echo "FAIL: no-GPU error does not name --device gpu: $(cat "$work/stderr")"; failures=$((failures + 1)); }
fi
expect 2 "both --mesh and --lattice" -- "$tetiso" extract --mesh "$meshes/cube.1" --lattice 10 -o "$out/t.ply"
expect 2 "missing mesh" -- "$tetiso" extract --mesh "$out/none" -o "$out/t.ply"
expect 2 "mesh attribute it lacks" -- "$tetiso" extract --mesh "$meshes/cube.1" --attribute 0 -o "$out/t.ply"
expect 2 "mesh with several domains" -- "$tetiso" extract --mesh "$meshes/cube.1" --domains 4 -o "$out/t.ply"
# The job over the mesh: split by a partition file (mpmetis's format) or METIS.
awk 'NR > 1 && !/^#/ { print NR % 3 }' "$meshes/cube.1.ele" >"$work/three.part"
expect 0 "run over a partitioned mesh" -- "$tetiso" run --mesh "$meshes/cube.1" --partition "$work/three.part" --field torus --quiet -o "$out/t.vtp" --report "$out/r.json"
expect 2 "run with both --mesh and --lattice" -- "$tetiso" run --mesh "$meshes/cube.1" --lattice 10 -o "$out/t.ply"
expect 2 "run with neither --mesh nor --lattice" -- "$tetiso" run --domains 4 -o "$out/t.ply"
expect 2 "partition without a mesh" -- "$tetiso" run --lattice 10 --partition "$work/three.part" -o "$out/t.ply"
expect 2 "partition of another domain count" -- "$tetiso" run --mesh "$meshes/cube.1" --partition "$work/three.part" --domains 4 -o "$out/t.ply"
head -n 100 "$work/three.part" >"$work/short.part"
expect 2 "partition shorter than the mesh" -- "$tetiso" run --mesh "$meshes/cube.1" --partition "$work/short.part" -o "$out/t.ply"
if grep -q "short.part: 100 domain ids for the mesh's 16251 tetrahedra" "$work/stderr"; then
    passed=$((passed + 1))
else
    echo "FAIL: a short partition's error names neither the file nor the counts: $(cat "$work/stderr")"
    failures=$((failures + 1))
fi
expect 2 "missing partition file" -- "$tetiso" run --mesh "$meshes/cube.1" --partition "$work/none.part" -o "$out/t.ply"

# The mesh split once into one file per domain: the job over the split is the
# job over the mesh, byte for byte; and what goes wrong with a split is said.
"$tetiso" split --mesh "$meshes/cube.1" --partition "$work/three.part" --field torus --quiet -o "$work/split3" &&
    "$tetiso" run --split "$work/split3" --quiet -o "$work/split3.ply" &&
    "$tetiso" run --mesh "$meshes/cube.1" --partition "$work/three.part" --field torus --quiet -o "$work/mesh3.ply"
if [ $? -eq 0 ] && cmp -s "$work/split3.ply" "$work/mesh3.ply"; then
    passed=$((passed + 1))
else
    echo "FAIL: the job over a split differs from the job over the mesh"; failures=$((failures + 1))
fi
# A split into one domain has no shared edges, empty arrays in its files.
expect 0 "split into one domain" -- "$tetiso" split --mesh "$meshes/cube.1" --field sphere --domains 1 --quiet -o "$out/s1"
"$tetiso" split --mesh "$meshes/cube.1" --field sphere --domains 1 --quiet -o "$work/split1"
expect 0 "run over a one-domain split" -- "$tetiso" run --split "$work/split1" --quiet -o "$out/s1.ply"
expect 2 "split without --domains or --partition" -- "$tetiso" split --mesh "$meshes/cube.1" -o "$out/s"
expect 2 "split of a missing mesh" -- "$tetiso" split --mesh "$out/none" --domains 2 -o "$out/s"
expect 2 "split into a directory that holds files" -- "$tetiso" split --mesh "$meshes/cube.1" --partition "$work/three.part" -o "$work/split3"
expect 2 "run over a missing split" -- "$tetiso" run --split "$work/none" -o "$out/t.ply"
expect 2 "run over a split with --field" -- "$tetiso" run --split "$work/split3" --field paper -o "$out/t.ply"
expect 2 "run over a split with --mesh" -- "$tetiso" run --split "$work/split3" --mesh "$meshes/cube.1" -o "$out/t.ply"
cp -r "$work/split3" "$work/damaged"
python3 -c "
import sys; p = sys.argv[1]; b = bytearray(open(p, 'rb').read()); b[len(b) // 2] ^= 1; open(p, 'wb').write(b)" "$work/damaged/domain-1.tetiso"
expect 2 "run over a split with a damaged domain file" -- "$tetiso" run --split "$work/damaged" --quiet -o "$out/t.ply"
if grep -q "damaged/domain-1.tetiso: damaged" "$work/stderr"; then
    passed=$((passed + 1))
else
    echo "FAIL: a damaged domain file's error does not name it: $(cat "$work/stderr")"; failures=$((failures + 1))
fi

# A command's outputs succeed or fail together: under a file-size limit of
# 3 KiB a small sphere (2.4 KB) fits and the report (7 KB) does not, and
# neither may be left behind. The error names the output, not its
# temporary, and says why.
# (extract's report is shorter than its surface: the surface fails there.)
expect 2 "run with a report past the file-size limit" -- bash -c 'ulimit -f 3; exec "$@"' - \
    "$tetiso" run --lattice 5 --domains 8 --field sphere --quiet -o "$out/e.ply" --report "$out/r.json"
failed_write() {
    grep -qE "$1: cannot write: File too large$" "$work/stderr" && ! grep -qE "\.(ply|json)\.tmp\." "$work/stderr" &&
        passed=$((passed + 1)) ||
        { echo "FAIL: a failed write's error: $(cat "$work/stderr")"; failures=$((failures + 1)); }
}
failed_write out/r.json
expect 2 "extract past the file-size limit" -- bash -c 'ulimit -f 1; exec "$@"' - "$tetiso" extract --lattice 30 -o "$out/big.ply"
failed_write out/big.ply
# A split that cannot be written says which file and why (it said only
# "cannot write"), and leaves no directory.
expect 2 "split past the file-size limit" -- bash -c 'ulimit -f 8; exec "$@"' - \
    "$tetiso" split --mesh "$meshes/cube.1" --domains 1 --field sphere -o "$out/s"
failed_write "out/s/domain-0.tetiso"
# A reduced tetrahedron-sized sphere: 1.8 KB of surface, 3.9 KB of report.
"$tetiso" extract --lattice 5 --field sphere -o "$work/tiny.ply"
"$tetiso" reduce "$work/tiny.ply" --phi 0.1 -o "$work/r.ply" --report "$work/r.json" 2>/dev/null
limit=$(( ($(wc -c <"$work/r.ply") + 1023) / 1024 ))
if [ "$(wc -c <"$work/r.json")" -gt $((limit * 1024)) ]; then
    expect 2 "reduce with a report past the file-size limit" -- bash -c "ulimit -f $limit"'; exec "$@"' - \
        "$tetiso" reduce "$work/tiny.ply" --phi 0.1 -o "$out/r.ply" --report "$out/r.json"
    failed_write out/r.json
else
    echo "FAIL: the reduce report no longer outgrows its surface; the test needs another case"; failures=$((failures + 1))
fi

# An output path that is not a regular file is refused, never replaced by
# one (as root, -o of /dev/null would have replaced the device); a symbolic
# link is written through, to the file it names, and stays a link.
mkfifo "$out/pipe.json"
"$tetiso" extract --lattice 10 -o "$work/p.ply" --report "$out/pipe.json" 2>"$work/stderr"
if [ $? -eq 2 ] && [ -p "$out/pipe.json" ] && [ ! -e "$work/p.ply" ] && grep -q "pipe.json: cannot write: it is a pipe" "$work/stderr"; then
    passed=$((passed + 1))
else
    echo "FAIL: a pipe as the report: $(cat "$work/stderr")"; failures=$((failures + 1))
fi
rm -f "$out/pipe.json"
mkdir -p "$work/elsewhere" && rm -f "$work/elsewhere/target.ply" "$work/link.ply"
ln -s "$work/elsewhere/target.ply" "$work/link.ply"
if "$tetiso" extract --lattice 10 -o "$work/link.ply" && [ -L "$work/link.ply" ] && [ -s "$work/elsewhere/target.ply" ] &&
    [ -z "$(ls "$work/elsewhere" | grep tmp)" ]; then
    passed=$((passed + 1))
else
    echo "FAIL: an output through a symbolic link"; failures=$((failures + 1))
fi

# A writer killed before it could clean up (SIGKILL; SIGXFSZ before tetiso
# ignored it) leaves OUT.tmp.PID.N: the next write of OUT removes those whose
# process is gone, and only those.
touch "$work/again.ply.tmp.4194399.17" "$work/again.ply.tmp.$$.18" "$work/again.ply.tmp.notes"
"$tetiso" extract --lattice 10 -o "$work/again.ply"
if [ ! -e "$work/again.ply.tmp.4194399.17" ] && [ -e "$work/again.ply.tmp.$$.18" ] && [ -e "$work/again.ply.tmp.notes" ]; then
    passed=$((passed + 1))
else
    echo "FAIL: stale temporaries: $(ls "$work" | grep again)"; failures=$((failures + 1))
fi

# An error that quotes a file's bytes stays on one line: a newline or a
# control byte in a VTP attribute is escaped.
"$tetiso" extract --lattice 8 --field sphere -o "$work/quoted.vtp"
python3 -c "
import sys; p = sys.argv[1]; b = open(p, 'rb').read()
open(p, 'wb').write(b.replace(b'NumberOfPoints=\"', b'NumberOfPoints=\"1\n2\x1b[31m', 1))" "$work/quoted.vtp"
expect 2 "an attribute with a newline" -- "$tetiso" check "$work/quoted.vtp"
grep -qF '1\n2\x1b[31m' "$work/stderr" && passed=$((passed + 1)) ||
    { echo "FAIL: control bytes are not escaped: $(cat -A "$work/stderr")"; failures=$((failures + 1)); }

# A level outside the range: an empty surface, said so on stderr in the same
# words by every command that extracts, exit 0.
for command in "extract --lattice 10" "run --lattice 10 --domains 4 --quiet" "run --mesh $meshes/cube.1 --partition $work/three.part --quiet"; do
    rm -f "$work/empty.ply"
    # shellcheck disable=SC2086
    "$tetiso" $command --field sphere --level 50 -o "$work/empty.ply" 2>"$work/stderr"
    if [ $? -eq 0 ] && grep -qE "^tetiso: the surface is empty: level 50 is outside the field's range \[0(\.[0-9]+)?, [0-9.]+\]$" "$work/stderr" &&
        [ "$(wc -l <"$work/stderr")" -eq 1 ] && [ -s "$work/empty.ply" ]; then
        passed=$((passed + 1))
    else
        echo "FAIL: $command: level outside the range: $(cat "$work/stderr")"; failures=$((failures + 1))
    fi
done

# A reduction's output carries its bounds: reducing it again under a tighter
# bound leaves the triangles already past it as they are, says so, exit 0.
"$tetiso" run --lattice 20 --domains 4 --field sphere --quiet -o "$work/bounded.vtp" &&
    "$tetiso" reduce "$work/bounded.vtp" --max-error 1e-6 -o "$work/again.vtp" 2>"$work/stderr"
if [ $? -eq 0 ] && grep -q "already carry an error bound above --max-error" "$work/stderr" && [ -s "$work/again.vtp" ]; then
    passed=$((passed + 1))
else
    echo "FAIL: reduce of a bounded surface under a tighter bound"; failures=$((failures + 1))
fi

# The report holds what the issue asks for, and the surface checks out.
"$tetiso" extract --lattice 30 --domains 8 --field sphere -o "$work/s.ply" --report "$work/r.json" &&
python3 - "$work/r.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for key in ("tets", "domains", "vertices", "triangles", "seconds"):
    assert key in r, key
assert r["domains"] == 8 and r["tets"] == 6 * 29 ** 3 and r["triangles"] > 0
assert all(v >= 0 for v in r["seconds"].values())
PY
if [ $? -eq 0 ]; then passed=$((passed + 1)); else echo "FAIL: report contents"; failures=$((failures + 1)); fi

"$tetiso" check "$work/s.ply" >"$work/check.json" && python3 - "$work/check.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["topology"]
assert c["components"] == 1 and c["euler"] == 2 and c["closed"] and c["manifold"] and c["oriented"], c
PY
if [ $? -eq 0 ]; then passed=$((passed + 1)); else echo "FAIL: tetiso check of an extracted sphere"; failures=$((failures + 1)); fi

# The same file for any domain count (README's promise).
"$tetiso" extract --lattice 40 --domains 1 -o "$work/d1.ply" && "$tetiso" extract --lattice 40 --domains 8 -o "$work/d8.ply" &&
    "$tetiso" extract --lattice 40 --domains 27 -o "$work/d27.ply"
if cmp -s "$work/d1.ply" "$work/d8.ply" && cmp -s "$work/d1.ply" "$work/d27.ply"; then passed=$((passed + 1)); else
    echo "FAIL: output depends on the domain count"; failures=$((failures + 1)); fi

# The same file for any thread count.
"$tetiso" extract --lattice 40 --threads 1 -o "$work/t1.ply" && "$tetiso" extract --lattice 40 --threads 2 -o "$work/t2.ply"
if cmp -s "$work/t1.ply" "$work/t2.ply"; then passed=$((passed + 1)); else echo "FAIL: output depends on threads"; failures=$((failures + 1)); fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
