"""Run under mpirun (test_insitu.sh): every rank hands its piece of the cube
fixture (a slab of tetrahedra plus a layer of ghost cells) to
tetiso.InSituSession; rank 0 writes the surface and the pieces as a .pvtu,
which test_insitu.sh gives to `tetiso run --mesh` to compare bytes. Checks
here: a surface on the root alone, the same bytes from a second call (a time
loop) and from the call's own output, this rank's cost, and one piece's
error raised on every rank with the same message.
Usage: insitu_check.py MESH.vtu OUTDIR"""
import pathlib
import sys

import numpy as np
from mpi4py import MPI

import tetiso
from vtu_fixture import read_ascii_vtu, write_ascii_vtu, write_pvtu

mesh, out = sys.argv[1], pathlib.Path(sys.argv[2])
comm = MPI.COMM_WORLD
rank, size = comm.rank, comm.size
points, tets, distance = read_ascii_vtu(mesh, "distance")
slab = np.minimum((points[tets].mean(axis=1)[:, 0] / 5.0 * size).astype(int), size - 1)


def piece(r):
    """Slab r's tetrahedra, then the others' that touch its nodes as ghosts."""
    own = slab == r
    ghost = ~own & np.isin(tets, tets[own]).any(axis=1)
    cells = np.concatenate([tets[own], tets[ghost]])
    marks = np.concatenate([np.zeros(own.sum(), np.uint8), np.ones(ghost.sum(), np.uint8)])
    nodes = np.unique(cells)
    return points[nodes], nodes.astype(np.int64), distance[nodes], np.searchsorted(nodes, cells).astype(np.int32), marks


if rank == 0:
    names = []
    for r in range(size):
        p = piece(r)
        names.append(f"piece_{r}.vtu")
        write_ascii_vtu(out / names[-1], p[0], p[3], {"distance": p[2], "GlobalNodeIds": p[1]}, p[4])
    write_pvtu(out / "pieces.pvtu", names, {"distance": np.float64, "GlobalNodeIds": np.int64})

p_points, p_ids, p_field, p_tets, p_ghosts = piece(rank)
with tetiso.InSituSession(comm) as session:
    assert (session.rank, session.size) == (rank, size)
    first = session.isosurface(p_points, p_ids, p_field, p_tets, 3.0, ghost_cells=p_ghosts)
    cost = session.last_cost
    assert cost["tetrahedra"] == int((slab == rank).sum()), cost
    assert cost["mesh_tetrahedra"] == len(tets) and cost["seconds"]["total"] > 0, cost
    # float32 positions and values, bool ghost marks, int64 tetrahedra: other dtypes, the same piece
    again = session.isosurface(p_points.astype(np.float32), p_ids, p_field.astype(np.float32),
                               p_tets.astype(np.int64), 3.0, ghost_cells=p_ghosts.astype(bool),
                               output=out / "insitu-written.ply")
    if rank == 0:
        assert first is not None and first.triangle_count > 0
        first.write(out / "insitu.ply")
        again.write(out / "insitu-again.ply")
    else:
        assert first is None and again is None

    broken = p_tets.copy()
    if rank == size - 1:
        broken[0, 0] = len(p_points)
    try:
        session.isosurface(p_points, p_ids, p_field, broken, 3.0, ghost_cells=p_ghosts)
        message = None
    except tetiso.Error as error:
        message = str(error)
    messages = comm.allgather(message)
    assert messages[0] is not None and all(m == messages[0] for m in messages), messages
    assert f"rank {size - 1}" in messages[0], messages[0]
if rank == 0:
    print("in situ on", size, "ranks:", first.triangle_count, "triangles; a bad piece:", messages[0])
