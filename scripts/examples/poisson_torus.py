#!/usr/bin/python3
"""A solver's result for tetiso: Poisson's equation on a solid torus, solved
with FEniCSx on as many MPI ranks as it is started with, written as
ParaView's partitioned .pvtu (one .vtu piece per rank).

  -laplace(u) = 1 in the torus, u = 0 on its surface

Gmsh meshes the torus (major radius 1, minor radius 0.4), DOLFINx solves
with piecewise linear elements and writes u. Every level set of u strictly
between 0 and its maximum is a torus again (genus 1): tetiso's surface of
such a level must have one closed component of genus 1.

Usage: mpirun -np K python3 poisson_torus.py OUTDIR [--size H]
Writes OUTDIR/poisson.pvtu, its pieces, and OUTDIR/poisson.json (the
maximum of u, the cells and nodes of the mesh).
"""
import json
import os
import sys

import gmsh
import numpy as np
import ufl
from dolfinx import fem, io
from dolfinx.io import gmshio
from dolfinx.mesh import exterior_facet_indices
from mpi4py import MPI
from petsc4py.PETSc import ScalarType


def mesh_torus(size):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    if MPI.COMM_WORLD.rank == 0:
        gmsh.model.add("torus")
        torus = gmsh.model.occ.addTorus(0, 0, 0, 1.0, 0.4)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [torus], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", size / 2)
        gmsh.model.mesh.generate(3)
    mesh, _, _ = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)
    gmsh.finalize()
    return mesh


def main():
    out = sys.argv[1]
    size = float(sys.argv[sys.argv.index("--size") + 1]) if "--size" in sys.argv else 0.1
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        os.makedirs(out, exist_ok=True)
    mesh = mesh_torus(size)
    V = fem.FunctionSpace(mesh, ("Lagrange", 1))
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    boundary = exterior_facet_indices(mesh.topology)
    dofs = fem.locate_dofs_topological(V, mesh.topology.dim - 1, boundary)
    bc = fem.dirichletbc(ScalarType(0), dofs, V)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    L = ScalarType(1) * v * ufl.dx
    problem = fem.petsc.LinearProblem(a, L, bcs=[bc], petsc_options={"ksp_type": "cg", "pc_type": "jacobi",
                                                                     "ksp_rtol": 1e-12})
    uh = problem.solve()
    uh.name = "u"
    with io.VTKFile(comm, os.path.join(out, "poisson.pvtu"), "w") as vtk:
        vtk.write_function(uh)
    owned = V.dofmap.index_map.size_local
    u_max = comm.allreduce(float(uh.x.array[:owned].max()), op=MPI.MAX)
    cells = mesh.topology.index_map(3).size_global
    nodes = mesh.geometry.index_map().size_global
    if comm.rank == 0:
        with open(os.path.join(out, "poisson.json"), "w") as f:
            json.dump({"u_max": u_max, "cells": cells, "nodes": nodes, "ranks": comm.size}, f)
        print(f"poisson_torus: {nodes} nodes, {cells} tetrahedra on {comm.size} ranks, max u = {u_max:.6g}")


if __name__ == "__main__":
    main()
