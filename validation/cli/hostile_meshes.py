#!/usr/bin/python3
"""Writes meshes whose tetrahedra overlap, for test_cli_hostile.sh and
tools/probe_hostile.sh: each made from the small solver meshes in
meshes/solver/ (ascii, so that a cell can be edited as text).

Usage: hostile_meshes.py MESHES_DIR OUT_DIR

  repeated.vtu      the cube with one tetrahedron listed twice (cell 1296
                    repeats cell 7)
  renumbered.vtu    the same after a triangle cell (a boundary marker):
                    tetrahedron 1296 is cell 1297
  tangled.vtu       the cube, every tetrahedron listed positively, with an
                    interior node moved 1.5 edge lengths, across its
                    neighbours' faces: the tetrahedra it inverts are named
  tangled-mixed.vtu the same from the cube as listed, half its tetrahedra
                    in either order: the listing names none, a pair is
  negative.vtu      the cube with every tetrahedron listed in negative order
                    (a convention, read)
  repeated.msh      Gmsh 2.2, element 1297 repeats element 1
  repeated.1.node/.ele  TetGen, tetrahedron 1296 repeats tetrahedron 0
  halves.pvtu       the cube in two pieces of 648 tetrahedra (read)
  inside.pvtu       the whole cube, and a piece of the tetrahedra around its
                    centre node (inside the first): they overlap
  apart.pvtu        the two halves with the second's node ids moved past the
                    first's: no node id shared (read, with a note)
  tangled.pvtu      the halves, the first from tangled.vtu
"""
import os
import re
import sys


def read_vtu(path):
    text = open(path).read()
    arrays = {}
    for name in ("distance", "Points", "connectivity", "offsets", "types"):
        m = re.search(r'Name="%s"[^>]*>\n(.*?)\n</DataArray>' % name, text, re.S)
        arrays[name] = m.group(1).split()
    points = [tuple(float(v) for v in arrays["Points"][3 * i:3 * i + 3]) for i in range(len(arrays["Points"]) // 3)]
    conn = [int(v) for v in arrays["connectivity"]]
    tets = [conn[4 * t:4 * t + 4] for t in range(len(conn) // 4)]
    return points, [float(v) for v in arrays["distance"]], tets


def write_vtu(path, points, values, cells, ids=None):
    """cells: lists of point indices; 4 corners a tetrahedron, 3 a triangle."""
    connectivity = " ".join(str(v) for c in cells for v in c)
    offsets, at = [], 0
    for c in cells:
        at += len(c)
        offsets.append(str(at))
    types = " ".join("10" if len(c) == 4 else "5" for c in cells)
    id_array = ""
    if ids is not None:
        id_array = ('<DataArray type="Int64" Name="GlobalNodeIds" format="ascii">\n%s\n</DataArray>\n'
                    % " ".join(str(i) for i in ids))
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian">\n'
                  '<UnstructuredGrid>\n<Piece NumberOfPoints="%d" NumberOfCells="%d">\n'
                  '<PointData Scalars="distance"%s>\n'
                  '<DataArray type="Float64" Name="distance" format="ascii">\n%s\n</DataArray>\n%s</PointData>\n'
                  '<Points>\n<DataArray type="Float64" NumberOfComponents="3" format="ascii">\n%s\n</DataArray>\n</Points>\n'
                  '<Cells>\n<DataArray type="Int64" Name="connectivity" format="ascii">\n%s\n</DataArray>\n'
                  '<DataArray type="Int64" Name="offsets" format="ascii">\n%s\n</DataArray>\n'
                  '<DataArray type="UInt8" Name="types" format="ascii">\n%s\n</DataArray>\n</Cells>\n'
                  '</Piece>\n</UnstructuredGrid>\n</VTKFile>\n'
                  % (len(points), len(cells), ' GlobalIds="GlobalNodeIds"' if ids is not None else "",
                     " ".join(repr(v) for v in values), id_array,
                     " ".join("%r %r %r" % p for p in points), connectivity, " ".join(offsets), types))


def volume6(points, t):
    a, b, c, d = (points[i] for i in t)
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    w = [d[k] - a[k] for k in range(3)]
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0]))


def write_pvtu(path, pieces):
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0">\n'
                  '<PUnstructuredGrid GhostLevel="0">\n<PPointData GlobalIds="GlobalNodeIds">\n'
                  '<PDataArray type="Float64" Name="distance"/>\n<PDataArray type="Int64" Name="GlobalNodeIds"/>\n'
                  '</PPointData>\n<PPoints>\n<PDataArray type="Float64" NumberOfComponents="3"/>\n</PPoints>\n%s'
                  '</PUnstructuredGrid>\n</VTKFile>\n' % "".join('<Piece Source="%s"/>\n' % p for p in pieces))


def main(meshes, out):
    points, values, tets = read_vtu(os.path.join(meshes, "solver", "cube-ascii.vtu"))
    ids = list(range(len(points)))
    write_vtu(os.path.join(out, "repeated.vtu"), points, values, tets + [tets[7]])
    write_vtu(os.path.join(out, "renumbered.vtu"), points, values, [tets[0][:3]] + tets + [tets[7]])
    negative = [t if volume6(points, t) < 0 else [t[0], t[1], t[3], t[2]] for t in tets]
    write_vtu(os.path.join(out, "negative.vtu"), points, values, negative)
    # The node nearest the centre, moved 1.5 edge lengths along x.
    centre = min(range(len(points)), key=lambda i: sum((p - 2.5) ** 2 for p in points[i]))
    moved = list(points)
    moved[centre] = (points[centre][0] + 1.25, points[centre][1], points[centre][2])  # an edge is 5/6
    positive = [[t[0], t[1], t[3], t[2]] if volume6(points, t) < 0 else t for t in tets]
    write_vtu(os.path.join(out, "tangled.vtu"), moved, values, positive)
    write_vtu(os.path.join(out, "tangled-mixed.vtu"), moved, values, tets)

    # Gmsh 2.2: element 1 again, as element 1297.
    msh = open(os.path.join(meshes, "solver", "cube-2.2.msh")).read()
    head, rest = msh.split("$Elements\n", 1)
    count, rest = rest.split("\n", 1)
    first = rest.split("\n", 1)[0]
    again = "%d %s" % (int(count) + 1, first.split(" ", 1)[1])
    body, tail = rest.split("$EndElements\n", 1)
    open(os.path.join(out, "repeated.msh"), "w").write(
        head + "$Elements\n%d\n%s%s\n$EndElements\n%s" % (int(count) + 1, body, again, tail))

    # TetGen: tetrahedron 0 again at the end.
    node = open(os.path.join(meshes, "cube.1.node")).read()
    open(os.path.join(out, "repeated.1.node"), "w").write(node)
    lines = open(os.path.join(meshes, "cube.1.ele")).read().split("\n")
    header = lines[0].split()
    body = [l for l in lines[1:] if l.strip() and not l.lstrip().startswith("#")]
    base = int(body[0].split()[0])
    again = " ".join([str(base + len(body))] + body[0].split()[1:])
    open(os.path.join(out, "repeated.1.ele"), "w").write(
        " ".join([str(int(header[0]) + 1)] + header[1:]) + "\n" + "\n".join(body + [again]) + "\n")

    # Pieces: the tetrahedra on either side of x = 2.5 (by their centroid).
    def centroid_x(t):
        return sum(points[i][0] for i in t) / 4
    low = [t for t in tets if centroid_x(t) < 2.5]
    high = [t for t in tets if centroid_x(t) >= 2.5]
    write_vtu(os.path.join(out, "low.vtu"), points, values, low, ids)
    write_vtu(os.path.join(out, "high.vtu"), points, values, high, ids)
    write_pvtu(os.path.join(out, "halves.pvtu"), ["low.vtu", "high.vtu"])
    write_vtu(os.path.join(out, "whole.vtu"), points, values, tets, ids)
    write_vtu(os.path.join(out, "core.vtu"), points, values, [t for t in tets if centre in t], ids)
    write_pvtu(os.path.join(out, "inside.pvtu"), ["whole.vtu", "core.vtu"])
    write_vtu(os.path.join(out, "high-apart.vtu"), points, values, high, [i + len(points) for i in ids])
    write_pvtu(os.path.join(out, "apart.pvtu"), ["low.vtu", "high-apart.vtu"])
    tangled_low = [t for t in tets if centroid_x(t) < 2.5 or centre in t]
    tangled_high = [t for t in high if centre not in t]
    write_vtu(os.path.join(out, "tangled-low.vtu"), moved, values, tangled_low, ids)
    write_vtu(os.path.join(out, "tangled-high.vtu"), moved, values, tangled_high, ids)
    write_pvtu(os.path.join(out, "tangled.pvtu"), ["tangled-low.vtu", "tangled-high.vtu"])


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
