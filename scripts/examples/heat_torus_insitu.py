#!/usr/bin/python3
"""A solver calling tetiso in situ at every step of its time loop: heat
spreading through a solid torus, solved with FEniCSx on as many MPI ranks as
it is started with, and at each step the reduced isosurface u = max(u)/2 made
by tetiso from the solver's own arrays, on the same ranks, with no mesh or
field file in between: only the surfaces are written.

  du/dt - laplace(u) = 1 in the torus, u = 0 on its surface, u = 0 at t = 0

(implicit Euler). Every level set of u strictly between 0 and its maximum is
a torus again (genus 1), at every step. Gmsh meshes the torus as
poisson_torus.py does.

Each rank hands tetiso its piece as DOLFINx holds it: the geometry's
coordinates (mesh.geometry.x, read in place), the geometry's global node
numbers (its index map's, which DOLFINx's .pvtu writer calls
vtkOriginalPointIds), the cells' nodes, the ghost cells marked, and u at
the geometry's nodes.

Usage: mpirun -np K python3 heat_torus_insitu.py OUTDIR [--size H] [--steps S] [--dt T] [--pvtu]
Writes OUTDIR/surface-S.vtp for each step S (1, 2, ...) and OUTDIR/steps.json
(each step's time, level, triangles and the call's cost on rank 0). With
--pvtu, also the last step's u as OUTDIR/last.pvtu (DOLFINx's own writer), so
that a test can hold the in-situ surface to `tetiso run --mesh` on that file.
PYTHONPATH must reach the tetiso module (build/python in a build tree).
"""
import json
import os
import sys

import numpy as np
import ufl
from dolfinx import fem, io
from dolfinx.mesh import exterior_facet_indices
from mpi4py import MPI
from petsc4py.PETSc import ScalarType

import tetiso

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from poisson_torus import mesh_torus  # noqa: E402


def option(name, default, kind=float):
    return kind(sys.argv[sys.argv.index(name) + 1]) if name in sys.argv else default


def main():
    out = sys.argv[1]
    size, steps, dt = option("--size", 0.1), option("--steps", 5, int), option("--dt", 0.02)
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        os.makedirs(out, exist_ok=True)
    mesh = mesh_torus(size)
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    dofs = fem.locate_dofs_topological(V, mesh.topology.dim - 1, exterior_facet_indices(mesh.topology))
    bc = fem.dirichletbc(ScalarType(0), dofs, V)
    u_old = fem.Function(V)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = (u * v + dt * ufl.inner(ufl.grad(u), ufl.grad(v))) * ufl.dx
    L = (u_old + dt * ScalarType(1)) * v * ufl.dx
    problem = fem.petsc.LinearProblem(a, L, bcs=[bc], petsc_options={"ksp_type": "cg", "pc_type": "jacobi",
                                                                     "ksp_rtol": 1e-12})

    # The piece, as DOLFINx holds it. A P1 space on a linear mesh has one dof
    # per geometry node, in the same place of each cell's list.
    points = mesh.geometry.x
    nodes = mesh.geometry.index_map()
    ids = nodes.local_to_global(np.arange(len(points), dtype=np.int32))
    cells = mesh.geometry.dofmap.array.reshape(-1, 4)
    cell_dofs = V.dofmap.list.array.reshape(-1, 4)
    owned_cells = mesh.topology.index_map(mesh.topology.dim).size_local
    ghosts = (np.arange(len(cells)) >= owned_cells).astype(np.uint8)
    values = np.zeros(len(points))

    session = tetiso.InSituSession(comm)
    record = []
    for step in range(1, steps + 1):
        uh = problem.solve()
        uh.x.scatter_forward()
        u_old.x.array[:] = uh.x.array
        values[cells] = uh.x.array[cell_dofs]
        owned = V.dofmap.index_map.size_local
        level = comm.allreduce(float(uh.x.array[:owned].max()), op=MPI.MAX) / 2
        surface = session.isosurface(points, ids, values, cells, level, ghost_cells=ghosts,
                                     output=os.path.join(out, f"surface-{step}.vtp"))
        if comm.rank == 0:
            record.append({"step": step, "time": step * dt, "level": level, "triangles": surface.triangle_count,
                           "cost": session.last_cost})
            print(f"heat_torus_insitu: step {step}, t = {step * dt:.3g}, level {level:.6g}: "
                  f"{surface.triangle_count} triangles in {session.last_cost['seconds']['total']:.3f} s")
    if "--pvtu" in sys.argv:
        uh.name = "u"
        with io.VTKFile(comm, os.path.join(out, "last.pvtu"), "w") as vtk:
            vtk.write_function(uh)
    session.close()
    if comm.rank == 0:
        with open(os.path.join(out, "steps.json"), "w") as f:
            json.dump({"ranks": comm.size, "size": size, "dt": dt, "steps": record}, f, indent=1)


if __name__ == "__main__":
    main()
