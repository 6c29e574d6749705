#!/usr/bin/env bash
# Replays the hostile-user probe behind README's "Bad input" table against a
# build, every row of it, and says per row whether it holds: the CLI cases
# (validation/cli/test_cli_hostile.sh: outputs over inputs, inputs that are
# not regular files, signals during a write, odd number notations,
# meaningless options, lower-dimensional cells, '+' values, tetrahedra and
# pieces that overlap, pieces that share no id), pieces as VTK's writer
# gives an unstreamed grid (every piece the whole mesh), the shared nodes'
# tolerance and the overlaps' gtests, the cell and piece order promise, the
# thread default on a loaded machine, and under mpirun: the fault cases
# (a worker killed, a worker and rank 0 stopped with kill -STOP), the same
# bytes for 1 to 4 ranks, and overlapping pieces refused alike on every rank.
# Not CI (it takes minutes and a quiet machine for the timings); CI runs the
# short tests it calls. Usage: tools/probe_hostile.sh [BUILD_DIR]
# (default build/; mpirun from PATH, skipped where there is none).
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(realpath "${1:-$root/build}")
tetiso=$build/core/tetiso
meshes=$root/meshes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
rows_passed=0
rows_failed=()

# row NAME COMMAND...: one row of the probe, its output kept in the log.
row() {
    local name=$1
    shift
    printf '%-58s' "$name"
    local start=$SECONDS
    if "$@" >"$work/row.log" 2>&1; then
        echo "holds ($((SECONDS - start)) s)"
        grep '^note: ' "$work/row.log" | sed 's/^/    /'
        rows_passed=$((rows_passed + 1))
    else
        echo "FAILS ($((SECONDS - start)) s)"
        grep -E '^FAIL' "$work/row.log" | sed 's/^/    | /'
        sed 's/^/    | /' "$work/row.log" | tail -8
        rows_failed+=("$name")
    fi
}

# Every piece the whole mesh, as vtkXMLPUnstructuredGridWriter writes a grid
# that its source does not stream (4 pieces, ghost level 1): refused by
# extract, run and split, naming the pieces.
vtk_whole_pieces() {
    python3 "$root/validation/cli/hostile_meshes.py" "$meshes" "$work" || return 1
    local pieces=""
    for p in 0 1 2 3; do
        cp "$work/whole.vtu" "$work/grid_$p.vtu"
        pieces+="<Piece Source=\"grid_$p.vtu\"/>"
    done
    sed "s|<Piece Source=\"whole.vtu\"/>|$pieces|; s|<Piece Source=\"core.vtu\"/>||; s|GhostLevel=\"0\"|GhostLevel=\"1\"|" \
        "$work/inside.pvtu" >"$work/grid.pvtu"
    local failed=0
    for command in "extract --level 1.5 -o $work/out.ply" "run --level 1.5 --quiet -o $work/out.ply" "split -o $work/out"; do
        # shellcheck disable=SC2086
        "$tetiso" $command --mesh "$work/grid.pvtu" --array distance 2>"$work/err"
        local status=$?
        if [ $status -ne 2 ] || ! grep -q "grid_1.vtu: the tetrahedron of node ids .* is also in .*grid_0.vtu" "$work/err"; then
            echo "$command: status $status: $(cat "$work/err")"
            failed=1
        fi
        [ ! -e "$work/out" ] && [ ! -e "$work/out.ply" ] || { echo "$command left an output"; failed=1; }
    done
    return $failed
}

# The triangles of a PLY as sets of corner positions, sorted: the surface
# whatever its triangle order.
cat >"$work/triangles.py" <<'PY'
import struct, sys
def triangles(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().split("\n")
    counts = {l.split()[1]: int(l.split()[2]) for l in header if l.startswith("element")}
    vertex_bytes = 21
    at = end
    points = [struct.unpack_from("<3f", data, at + vertex_bytes * v) for v in range(counts["vertex"])]
    at += vertex_bytes * counts["vertex"]
    extra = 4 if "tetiso_error_bound" in data[:end].decode() else 0
    out = []
    for t in range(counts["face"]):
        a, b, c = struct.unpack_from("<3i", data, at + 1)
        at += 13 + extra
        corners = [points[a], points[b], points[c]]
        k = corners.index(min(corners))  # the same triangle, the same winding, from its least corner
        out.append(tuple(corners[k:] + corners[:k]))
    return points, sorted(out)
(p1, t1), (p2, t2) = triangles(sys.argv[1]), triangles(sys.argv[2])
sys.exit(0 if p1 == p2 and t1 == t2 else "different vertices or triangles")
PY

# The same mesh with its cells shuffled, and a .pvtu with its pieces in the
# other order: `extract` gives the same vertices (in key order) and
# triangles, as README promises, the triangle order aside. (`run` reduces
# over the decomposition, which for a .pvtu is its pieces in their order.)
cell_and_piece_order() {
    python3 - "$meshes/solver/cube-ascii.vtu" "$work/shuffled.vtu" <<'PY' || return 1
import random, re, sys
text = open(sys.argv[1]).read()
conn = re.search(r'Name="connectivity"[^>]*>\n(.*?)\n', text).group(1).split()
tets = [conn[i:i + 4] for i in range(0, len(conn), 4)]
random.Random(43).shuffle(tets)
open(sys.argv[2], "w").write(text.replace(" ".join(conn), " ".join(v for t in tets for v in t), 1))
PY
    "$tetiso" extract --mesh "$meshes/solver/cube-ascii.vtu" --array distance --level 1.5 -o "$work/cells.ply" &&
        "$tetiso" extract --mesh "$work/shuffled.vtu" --array distance --level 1.5 -o "$work/shuffled.ply" &&
        python3 "$work/triangles.py" "$work/cells.ply" "$work/shuffled.ply" || return 1
    cp "$meshes"/solver/pieces_*.vtu "$work/"
    sed -e 's|pieces_0.vtu|PIECE_A|' -e 's|pieces_2.vtu|pieces_0.vtu|' -e 's|PIECE_A|pieces_2.vtu|' \
        "$meshes/solver/pieces.pvtu" >"$work/reversed.pvtu"
    "$tetiso" extract --mesh "$meshes/solver/pieces.pvtu" --array distance --level 1.5 -o "$work/pieces.ply" &&
        "$tetiso" extract --mesh "$work/reversed.pvtu" --array distance --level 1.5 -o "$work/reversed.ply" &&
        python3 "$work/triangles.py" "$work/pieces.ply" "$work/reversed.ply"
}

# --threads at the core count on a machine under other load: the process
# waits passively (the CLI test checks the environment it runs with); the
# seconds of 1 and of all threads are printed, for the eye.
threads_under_load() {
    local cores
    cores=$(nproc)
    for threads in 1 "$cores"; do
        local start=$SECONDS
        "$tetiso" run --lattice 70 --domains 27 --threads "$threads" --quiet -o "$work/t$threads.ply" || return 1
        echo "note: run --lattice 70 --domains 27 --threads $threads: $((SECONDS - start)) s (load $(cut -d' ' -f1 /proc/loadavg))"
    done
    cmp "$work/t1.ply" "$work/t$cores.ply"
}

# The same bytes from 1 to 4 ranks, for a lattice and for a .pvtu.
ranks_agree() {
    local failed=0
    for k in 1 2 3 4; do
        mpirun --oversubscribe -np "$k" "$tetiso" run --lattice 40 --domains 8 --quiet -o "$work/lattice$k.ply" || failed=1
        mpirun --oversubscribe -np "$k" "$tetiso" run --mesh "$meshes/solver/pieces.pvtu" --array distance --level 1.5 \
            --quiet -o "$work/pieces$k.ply" || failed=1
        cmp "$work/lattice1.ply" "$work/lattice$k.ply" || failed=1
        cmp "$work/pieces1.ply" "$work/pieces$k.ply" || failed=1
    done
    return $failed
}

# Overlapping pieces under mpirun: every rank refuses alike, at once, the
# job ends with status 2 naming the piece, nothing written.
ranks_refuse_overlaps() {
    python3 "$root/validation/cli/hostile_meshes.py" "$meshes" "$work" || return 1
    local failed=0
    for k in 2 3; do
        timeout 60 mpirun --oversubscribe -np "$k" "$tetiso" run --mesh "$work/inside.pvtu" --array distance --level 1.5 \
            --quiet -o "$work/overlap.ply" 2>"$work/err"
        local status=$?
        if [ $status -ne 2 ] || ! grep -q "core.vtu: the tetrahedron of node ids .* reaches inside" "$work/err" ||
            [ -e "$work/overlap.ply" ]; then
            echo "-np $k: status $status: $(cat "$work/err")"
            failed=1
        fi
    done
    return $failed
}

[ -x "$tetiso" ] || { echo "no $tetiso: build the tetiso target first"; exit 2; }
echo "probe of $tetiso ($(git -C "$root" rev-parse --short HEAD)), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
row "CLI cases (test_cli_hostile.sh)" bash "$root/validation/cli/test_cli_hostile.sh" "$tetiso"
row "VTK's whole-mesh pieces, ghost level 1" vtk_whole_pieces
for test in test_solver_meshes test_mesh_overlaps; do
    if [ -x "$build/validation/$test" ]; then
        row "gtest $test" "$build/validation/$test"
    else
        echo "gtest $test: not built, skipped"
    fi
done
row "cell and piece order: the same surface" cell_and_piece_order
row "--threads at the core count" threads_under_load
if command -v mpirun >/dev/null; then
    row "MPI faults: killed, stopped worker, stopped rank 0, ..." bash "$root/validation/mpi/test_mpi_faults.sh" "$tetiso" mpirun
    row "MPI: the same bytes for 1-4 ranks" ranks_agree
    row "MPI: overlapping pieces refused on every rank" ranks_refuse_overlaps
else
    echo "no mpirun: the MPI rows skipped"
fi
echo "${rows_passed} rows hold, ${#rows_failed[@]} fail${rows_failed[*]:+: ${rows_failed[*]}}"
[ ${#rows_failed[@]} -eq 0 ]
