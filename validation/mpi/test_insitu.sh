#!/usr/bin/env bash
# The in-situ call against the file route (test_insitu.cpp makes both): for
# 1, 2 and 3 ranks the surface a solver's ranks get in memory is the bytes
# `tetiso run --mesh` writes for the same pieces as a .pvtu, ghost cells
# skipped; a second call of the session gives the same bytes; bad input on
# one rank, a domain task failing on one rank, overlapping pieces, a
# tetrahedron listed twice in one rank's piece and options that differ
# between ranks end the call on every rank with one message naming the
# rank, nothing written; the tetrahedron listed twice is refused in the
# words `tetiso run --mesh` uses for the same pieces as a .pvtu.
# Usage: test_insitu.sh tetiso mpiexec test_insitu
# TETISO_TEST_INSITU_DEVICE=gpu (or auto) runs the in-situ tasks on the
# ranks' GPUs, against the CPU's file route.
set -u
tetiso=$1
mpiexec=${2:-mpirun}
program=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source "$(dirname "$0")/mpi_support.sh"

# Every rank caught one message, the same on all, and it says what.
same_error() {
    local dir=$1 k=$2 expected=$3 what=$4
    local first="$dir/error-0.txt"
    for ((r = 0; r < k; r++)); do
        [ -s "$dir/error-$r.txt" ] && cmp -s "$first" "$dir/error-$r.txt" || { fail "$what: rank $r's message differs or is missing"; return; }
    done
    grep -q -- "$expected" "$first" && ok || fail "$what: message '$(cat "$first")' lacks '$expected'"
}

for k in 1 2 3; do
    dir="$work/same-$k"
    mkdir -p "$dir"
    if mpi "$k" "$program" same "$dir"; then
        if "$tetiso" run --quiet --mesh "$dir/pieces.pvtu" --array f --level "$(cat "$dir/level.txt")" -o "$dir/file.ply"; then
            cmp -s "$dir/file.ply" "$dir/insitu.ply" && ok || fail "$k ranks: the in-situ surface differs from tetiso run's"
        else
            fail "$k ranks: tetiso run on the pieces written"
        fi
        cmp -s "$dir/insitu.ply" "$dir/insitu2.ply" && ok || fail "$k ranks: a second call gave other bytes"
    else
        fail "$k ranks: the in-situ call"
    fi
    [ "$k" -gt 1 ] && cmp -s "$work/same-1/insitu.ply" "$dir/insitu.ply" && fail "$k ranks: the surface of one piece and of $k pieces are the same bytes (expected different seams)"

    dir="$work/bad-$k"
    mkdir -p "$dir"
    mpi "$k" "$program" bad "$dir" && ok || fail "$k ranks: bad input did not throw on every rank"
    same_error "$dir" "$k" "rank $((k - 1)): rank $((k - 1))'s piece: tetrahedron 1 refers to node" "$k ranks, bad input"

    dir="$work/flat-$k"
    mkdir -p "$dir"
    mpi "$k" "$program" flat "$dir" && ok || fail "$k ranks: a failing domain task did not throw on every rank"
    if [ "$k" -gt 1 ]; then
        same_error "$dir" "$k" "rank $((k - 1)): domain [0-9]* (rank $((k - 1))'s piece): rank $((k - 1))'s piece: tetrahedron 0 has zero volume" "$k ranks, failing task"
    else # no shared node to move: the scan refuses the flat tetrahedron, as the .pvtu route's does
        same_error "$dir" "$k" "^rank 0's piece: tetrahedron 0 (cell 0) has zero volume" "$k ranks, flat tetrahedron"
    fi

    # One message on every rank, and the file route's for the same pieces
    # but for the piece's name (a rank's piece, not a file).
    dir="$work/twice-$k"
    mkdir -p "$dir"
    mpi "$k" "$program" twice "$dir" && ok || fail "$k ranks: a tetrahedron listed twice did not throw on every rank"
    same_error "$dir" "$k" "rank $((k - 1))'s piece: tetrahedron [0-9]* (cell [0-9]*) repeats tetrahedron 0 (cell 0): the same four corners" "$k ranks, tetrahedron twice"
    if "$tetiso" run --quiet --mesh "$dir/pieces.pvtu" --array f --level 0 -o "$dir/file.ply" 2>"$dir/file-error.txt"; then
        fail "$k ranks: tetiso run took a piece with a tetrahedron listed twice"
    else
        file_words=$(sed -n "s|.*/piece_$((k - 1)).vtu: ||p" "$dir/file-error.txt")
        insitu_words=$(sed -n "s|.*rank $((k - 1))'s piece: ||p" "$dir/error-0.txt")
        [ -n "$file_words" ] && [ "$file_words" = "$insitu_words" ] && ok ||
            fail "$k ranks: tetrahedron twice: in situ '$insitu_words', file route '$file_words'"
        [ -e "$dir/file.ply" ] && fail "$k ranks: tetiso run left $dir/file.ply"
    fi

    dir="$work/options-$k"
    mkdir -p "$dir"
    if [ "$k" -gt 1 ]; then
        mpi "$k" "$program" options "$dir" && ok || fail "$k ranks: differing options did not throw on every rank"
        same_error "$dir" "$k" "rank $((k - 1)): its options (level, reduction, output) differ from rank 0's" "$k ranks, options"

        dir="$work/overlap-$k"
        mkdir -p "$dir"
        mpi "$k" "$program" overlap "$dir" && ok || fail "$k ranks: overlapping pieces did not throw on every rank"
        same_error "$dir" "$k" "pieces overlap" "$k ranks, overlap"
    fi
done

echo "test_insitu.sh: $passed passed, $failures failed"
[ "$failures" -eq 0 ]
