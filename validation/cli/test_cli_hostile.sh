#!/usr/bin/env bash
# What a hostile but realistic user tries against the `tetiso` command (issue
# 43's probe): outputs that name inputs or each other, inputs that are not
# regular files, signals during a write, numbers in odd notations, and
# options that mean nothing together, meshes whose tetrahedra or pieces
# overlap (hostile_meshes.py makes them). Each case is one row of README's
# "Bad input" table. Usage: test_cli_hostile.sh PATH/TO/tetiso [sanitized]
# ("sanitized": AddressSanitizer reserves terabytes of address space, so the
# memory limit below is left to the unsanitized run; the time limit stays.)
set -u
tetiso=$(realpath "$1")
sanitized=${2:-}
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
if [ -z "$sanitized" ]; then
    limited() { bash -c 'ulimit -v 1500000; exec timeout 20 "$@"' - "$@"; }
else
    limited() { timeout 20 "$@"; }
fi
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

# Integer options: decimal digits only, the same rule for every option;
# leading zeros do not make a number octal.
"$tetiso" extract --lattice 032 --domains 010 -o "$work/oct.ply" --report "$work/oct.json" &&
    "$tetiso" extract --lattice 32 -o "$work/dec.ply" && cmp -s "$work/oct.ply" "$work/dec.ply" &&
    grep -q '"domains": 10,' "$work/oct.json" && passed=$((passed + 1)) ||
    { echo "FAIL: --lattice 032 --domains 010 is not 32 and 10"; failures=$((failures + 1)); }
for option in "--lattice 0x20" "--lattice 1e3" "--domains 0x10" "--threads 0x10" "--gpu 0x1" "--lattice 32 --seam-rings 0x2"; do
    # shellcheck disable=SC2086 # the option and its value
    expect 2 "integer option $option" -- "$tetiso" run $option -o "$out/s.ply"
    says "is not a whole number in decimal digits"
done

# Messages: short, and naming what is wrong.
expect 2 "--gpu -1" -- "$tetiso" extract --lattice 10 --gpu -1 -o "$out/s.ply"
says "--gpu: must be at least 0, not -1"
[ "$(wc -c <"$work/stderr")" -lt 100 ] && passed=$((passed + 1)) ||
    { echo "FAIL: --gpu -1's message is long: $(wc -c <"$work/stderr") bytes"; failures=$((failures + 1)); }
for phi in 0 nan -0.5 1.5; do
    expect 2 "--phi $phi" -- "$tetiso" run --lattice 10 --domains 2 --quiet --phi "$phi" -o "$out/s.ply"
    says "--phi: $phi is outside (0, 1]"
done
python3 -c "
import sys; s = open(sys.argv[1]).read()
open(sys.argv[2], 'w').write(s.replace('format=\"ascii\">\n0 49 56 57', 'format=\"ascii\">\n1099511627776 49 56 57', 1))" \
    "$meshes/solver/cube-ascii.vtu" "$work/huge.vtu"
expect 2 "a connectivity value past int32" -- "$tetiso" extract --mesh "$work/huge.vtu" --array distance -o "$out/t.ply"
says "value 0 (1099511627776) is out of range"

# ASCII numbers with a leading '+', as VTK, Gmsh and TetGen read them.
python3 -c "
import sys; s = open(sys.argv[1]).read()
open(sys.argv[2], 'w').write(s.replace('4.330127239227295 3.9086', '+4.330127239227295 +3.9086', 1).replace('\n0 49 56 57', '\n+0 +49 56 57', 1))" \
    "$meshes/solver/cube-ascii.vtu" "$work/plus.vtu"
"$tetiso" extract --mesh "$meshes/solver/cube-ascii.vtu" --array distance --level 2 -o "$work/plain.ply" &&
    "$tetiso" extract --mesh "$work/plus.vtu" --array distance --level 2 -o "$work/plus.ply" 2>"$work/stderr" &&
    cmp -s "$work/plain.ply" "$work/plus.ply" && passed=$((passed + 1)) ||
    { echo "FAIL: a .vtu with '+' values: $(cat "$work/stderr")"; failures=$((failures + 1)); }
sed -e 's/^1 4.330127239227295$/1 +4.330127239227295/' -e 's/^2 0 0 0.8333333134651184$/2 +0 0 +0.8333333134651184/' \
    "$meshes/solver/cube-2.2.msh" >"$work/plus.msh"
"$tetiso" extract --mesh "$meshes/solver/cube-2.2.msh" --array distance --level 2 -o "$work/plain.ply" &&
    "$tetiso" extract --mesh "$work/plus.msh" --array distance --level 2 -o "$work/plus.ply" 2>"$work/stderr" &&
    cmp -s "$work/plain.ply" "$work/plus.ply" && ! cmp -s "$meshes/solver/cube-2.2.msh" "$work/plus.msh" &&
    passed=$((passed + 1)) || { echo "FAIL: a .msh with '+' values: $(cat "$work/stderr")"; failures=$((failures + 1)); }
for bad in "+-1" "++1" "+"; do
    python3 -c "
import sys; s = open(sys.argv[1]).read()
open(sys.argv[2], 'w').write(s.replace('4.330127239227295 3.9086', sys.argv[3] + ' 3.9086', 1))" \
        "$meshes/solver/cube-ascii.vtu" "$work/bad.vtu" "$bad"
    expect 2 "a .vtu value '$bad'" -- "$tetiso" extract --mesh "$work/bad.vtu" --array distance -o "$out/t.ply"
done

# A cell of a lower-dimensional type that lists the corners of a
# tetrahedron is a mistake, not a boundary marker to skip (it left a hole).
for type in 1 3 5 9; do
    python3 -c "
import sys; s = open(sys.argv[1]).read()
s = s.replace('format=\"ascii\">\n10 10 ', 'format=\"ascii\">\n10 ' + sys.argv[3] + ' ', 1)
open(sys.argv[2], 'w').write(s)" "$meshes/solver/cube-ascii.vtu" "$work/type.vtu" "$type"
    if [ "$type" = 9 ]; then # a quad has 4 corners: a boundary cell, skipped
        expect 0 "a cell of type 9 with 4 corners" -- "$tetiso" extract --mesh "$work/type.vtu" --array distance --level 2 -o "$out/t.ply"
    else
        expect 2 "a cell of type $type with 4 corners" -- "$tetiso" extract --mesh "$work/type.vtu" --array distance -o "$out/t.ply"
        says "cell 1 is a"
        says "with 4 corners"
    fi
done

# A tetrahedron of zero volume (its corners on one line) has no orientation:
# refused, named. One listed with its corners in the other order is read as
# the positive tetrahedron it is (each is oriented by its own corners).
python3 -c "
import sys; s = open(sys.argv[1]).read()
open(sys.argv[2], 'w').write(s.replace('format=\"ascii\">\n0 49 56 57', 'format=\"ascii\">\n0 1 2 3', 1))
open(sys.argv[3], 'w').write(s.replace('format=\"ascii\">\n0 49 56 57', 'format=\"ascii\">\n0 49 57 56', 1))" \
    "$meshes/solver/cube-ascii.vtu" "$work/flat.vtu" "$work/flipped.vtu"
expect 2 "a tetrahedron of zero volume" -- "$tetiso" extract --mesh "$work/flat.vtu" --array distance -o "$out/t.ply"
says "flat.vtu: tetrahedron 0 has zero volume"
"$tetiso" extract --mesh "$work/flipped.vtu" --array distance --level 2 -o "$work/flipped.ply" &&
    "$tetiso" extract --mesh "$meshes/solver/cube-ascii.vtu" --array distance --level 2 -o "$work/unflipped.ply" &&
    cmp -s "$work/flipped.ply" "$work/unflipped.ply" && passed=$((passed + 1)) ||
    { echo "FAIL: a tetrahedron in the other corner order"; failures=$((failures + 1)); }

# Tetrahedra that overlap where a mesh is read (hostile_meshes.py makes
# them): one listed twice (named by its position and, where other cells come
# before it, its cell or element number), in a .vtu, a .msh and a TetGen
# mesh; a tangled mesh (a node moved across its neighbours' faces), whose
# inverted tetrahedron is named where the mesh lists its tetrahedra in one
# orientation; a mesh listed all in negative order is a convention and reads
# to the same surface.
python3 "$(dirname "$0")/hostile_meshes.py" "$meshes" "$work"
expect 2 "a tetrahedron listed twice" -- "$tetiso" extract --mesh "$work/repeated.vtu" --array distance --level 1.5 -o "$out/t.ply"
says "repeated.vtu: tetrahedron 1296 repeats tetrahedron 7: the same four corners"
expect 2 "a tetrahedron listed twice after a triangle" -- "$tetiso" run --mesh "$work/renumbered.vtu" --array distance --level 1.5 --domains 2 --quiet -o "$out/t.ply"
says "renumbered.vtu: tetrahedron 1296 (cell 1297) repeats tetrahedron 7 (cell 8)"
expect 2 "a Gmsh element listed twice" -- "$tetiso" extract --mesh "$work/repeated.msh" --array distance --level 1.5 -o "$out/t.ply"
says "repeated.msh: tetrahedron 1296 (element 1297) repeats tetrahedron 0 (element 1)"
expect 2 "a TetGen tetrahedron listed twice" -- "$tetiso" split --mesh "$work/repeated.1" --field sphere --domains 2 -o "$out/s"
says "repeated.1.ele: tetrahedron 16251 repeats tetrahedron 0"
for command in "extract" "run --domains 2 --quiet"; do
    # shellcheck disable=SC2086
    expect 2 "$command on a tangled mesh" -- "$tetiso" $command --mesh "$work/tangled.vtu" --array distance --level 1.5 -o "$out/t.ply"
    says "tangled.vtu: tetrahedron 735 is inverted: negatively oriented where the mesh's tetrahedra are positively (all but 6)"
done
expect 2 "a tangled mesh of mixed orders" -- "$tetiso" extract --mesh "$work/tangled-mixed.vtu" --array distance --level 1.5 -o "$out/t.ply"
says "tangled-mixed.vtu: tetrahedron 516 and tetrahedron 735 lie on the same side of the face they share"
"$tetiso" extract --mesh "$work/negative.vtu" --array distance --level 1.5 -o "$work/negative.ply" &&
    "$tetiso" extract --mesh "$meshes/solver/cube-ascii.vtu" --array distance --level 1.5 -o "$work/positive.ply" &&
    cmp -s "$work/negative.ply" "$work/positive.ply" && passed=$((passed + 1)) ||
    { echo "FAIL: a mesh listed all in negative order"; failures=$((failures + 1)); }

# .pvtu pieces that overlap: one listed twice, one under two names, and
# pieces that each hold the whole mesh (as VTK's writer gives for a grid it
# does not stream). Refused before any task, naming a tetrahedron and both
# pieces.
sed 's|Source="pieces_2.vtu"|Source="pieces_1.vtu"|' "$meshes/solver/pieces.pvtu" >"$work/twice.pvtu"
sed 's|Source="pieces_2.vtu"|Source="./pieces_1.vtu"|' "$meshes/solver/pieces.pvtu" >"$work/two-names.pvtu"
sed -e 's|Source="pieces_1.vtu"|Source="pieces_0.vtu"|' -e 's|Source="pieces_2.vtu"|Source="pieces_0.vtu"|' \
    "$meshes/solver/pieces.pvtu" >"$work/whole.pvtu"
for pvtu in twice two-names whole; do
    for command in "extract" "run --quiet" "split"; do
        # shellcheck disable=SC2086
        expect 2 "$command over overlapping pieces ($pvtu)" -- "$tetiso" $command --mesh "$work/$pvtu.pvtu" --array distance -o "$out/t.ply"
        says "pieces overlap"
    done
done
says "pieces_0.vtu: the tetrahedron of node ids"
# A piece inside another (the tetrahedra around the cube's centre node, and
# the whole cube): found though the shared cells lie on one boundary only.
# A tangled piece, refused by the scan. Pieces that share no node id read,
# with one note naming them.
for command in "extract --level 1.5" "run --level 1.5 --quiet" "split"; do
    # shellcheck disable=SC2086
    expect 2 "$command over a piece inside another" -- "$tetiso" $command --mesh "$work/inside.pvtu" --array distance -o "$out/t.ply"
    says "core.vtu: the tetrahedron of node ids 114, 115, 122, 171 (cell 5) reaches inside"
    says "whole.vtu: node id 114 lies on no face of that piece's boundary: pieces overlap"
done
expect 2 "a tangled piece" -- "$tetiso" run --mesh "$work/tangled.pvtu" --array distance --level 1.5 --quiet -o "$out/t.ply"
says "tangled-low.vtu: tetrahedron 516 and tetrahedron 648 lie on the same side"
expect 0 "pieces that share no node id" -- "$tetiso" extract --mesh "$work/apart.pvtu" --array distance --level 1.5 -o "$out/t.ply"
says "tetiso: note: $work/apart.pvtu: the pieces fall into 2 groups that share no node id (piece 0 ($work/low.vtu); piece 1 ($work/high-apart.vtu))"
[ "$(wc -l <"$work/stderr")" -eq 1 ] && passed=$((passed + 1)) || { echo "FAIL: the note is not one line"; failures=$((failures + 1)); }
expect 0 "pieces that share node ids" -- "$tetiso" run --mesh "$work/halves.pvtu" --array distance --level 1.5 --quiet -o "$out/t.ply"
[ ! -s "$work/stderr" ] && passed=$((passed + 1)) || { echo "FAIL: halves.pvtu: $(cat "$work/stderr")"; failures=$((failures + 1)); }

# Options that mean nothing together, or nothing at all.
expect 2 "--array with --field" -- "$tetiso" extract --mesh "$meshes/solver/cube-ascii.vtu" --array distance --field sphere -o "$out/t.ply"
says "excludes --field"
expect 2 "--attribute with --field" -- "$tetiso" run --mesh "$meshes/cube.1" --domains 2 --attribute 0 --field sphere -o "$out/t.ply"
expect 2 "check --vertices-only without --against" -- "$tetiso" check "$work/keep.ply" --vertices-only
says "requires --against"
expect 2 "--node-ids ''" -- "$tetiso" extract --mesh "$meshes/solver/pieces.pvtu" --array distance --node-ids '' -o "$out/t.ply"
says "an empty value names nothing"
expect 2 "--array ''" -- "$tetiso" split --mesh "$meshes/solver/pieces.pvtu" --array '' -o "$out/s"
expect 2 "--gpu 7 with --device cpu" -- "$tetiso" extract --lattice 10 --device cpu --gpu 7 -o "$out/s.ply"
says "--gpu: applies with --device gpu"
expect 2 "--gpu 1 with the CPU by default" -- "$tetiso" reduce "$work/keep.ply" --gpu 1 -o "$out/r.ply"
python3 -c "
import sys; s = open(sys.argv[1]).read()
ghosts = '<CellData>\n<DataArray type=\"UInt8\" Name=\"vtkGhostType\" format=\"ascii\">\n' + ' '.join(['1'] * 1296) + '\n</DataArray>\n</CellData>\n'
open(sys.argv[2], 'w').write(s.replace('</PointData>\n', '</PointData>\n' + ghosts, 1))" "$meshes/solver/cube-ascii.vtu" "$work/ghosts.vtu"
expect 2 "a .vtu of ghost cells alone" -- "$tetiso" extract --mesh "$work/ghosts.vtu" --array distance -o "$out/t.ply"
says "no tetrahedra besides its 1296 ghost cells"
# Two $NodeData of one name and one time step: which is the field?
python3 -c "
import sys; s = open(sys.argv[1]).read()
a = s.index('\$NodeData'); b = s.index('\$EndNodeData') + len('\$EndNodeData\n')
open(sys.argv[2], 'w').write(s[:b] + s[a:b] + s[b:])" "$meshes/solver/cube-2.2.msh" "$work/twice.msh"
expect 2 "a .msh view twice" -- "$tetiso" extract --mesh "$work/twice.msh" --array distance -o "$out/t.ply"
says "appears twice for time step 0"

# A signal while the outputs are written (Ctrl-C, SIGTERM, SIGHUP): the
# temporaries are removed and the process ends by that signal. The signal is
# sent the moment a temporary appears.
for signal in INT TERM HUP; do
    rm -rf "$work/sig" && mkdir "$work/sig"
    python3 - "$signal" "$work/sig" "$tetiso" <<'PY'
import os, signal, subprocess, sys
name, folder, tetiso = sys.argv[1:]
number = getattr(signal, "SIG" + name)
# A loaded machine may let the write pass unseen: a few tries.
for attempt in range(5):
    job = subprocess.Popen([tetiso, "extract", "--lattice", "80", "-o", folder + "/s.ply", "--report", folder + "/r.json"],
                           stderr=subprocess.DEVNULL)
    while job.poll() is None and not any(".tmp." in f for f in os.listdir(folder)):
        pass
    if job.poll() is None:
        break
    for f in os.listdir(folder):
        os.remove(os.path.join(folder, f))
else:
    sys.exit("no temporary seen in 5 runs")
job.send_signal(number)
status = job.wait()
left = os.listdir(folder)
if status != -number or left:
    sys.exit(f"SIG{name}: status {status}, left {left}")
PY
    if [ $? -eq 0 ]; then passed=$((passed + 1)); else echo "FAIL: SIG$signal during a write"; failures=$((failures + 1)); fi
done

# libgomp's threads wait passively unless the user chose otherwise: the
# process runs with OMP_WAIT_POLICY=passive (set before libgomp is loaded,
# by executing itself again), and a policy the user set stands.
python3 - "$tetiso" "$work" <<'PY'
import os, subprocess, sys, time
tetiso, work = sys.argv[1:]
for given, expected in ((None, b"passive"), (b"active", b"active")):
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    if given:
        env["OMP_WAIT_POLICY"] = given.decode()
    job = subprocess.Popen([tetiso, "extract", "--lattice", "120", "-o", work + "/wait.ply"], env=env)
    seen = None
    deadline = time.time() + 60
    while job.poll() is None and time.time() < deadline:
        try:
            variables = open(f"/proc/{job.pid}/environ", "rb").read().split(b"\0")
        except OSError:
            break
        values = [v.split(b"=", 1)[1] for v in variables if v.startswith(b"OMP_WAIT_POLICY=")]
        if values:
            seen = values[0]
            break
    job.wait()
    if seen != expected:
        sys.exit(f"OMP_WAIT_POLICY given {given}: the process ran with {seen}, not {expected}")
PY
if [ $? -eq 0 ]; then passed=$((passed + 1)); else echo "FAIL: the wait policy"; failures=$((failures + 1)); fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
