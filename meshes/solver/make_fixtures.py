#!/usr/bin/python3
"""Writes the small solver-format meshes the tests read (meshes/solver/).

One mesh, a jittered 7x7x7 lattice on [0,5]^3 cut into 1,296 tetrahedra,
with the point array `distance` (distance to the cube's centre; level 1.5
is a sphere), in every encoding VTK and ParaView write and in Gmsh's
formats:

  cube-<encoding>.vtu   ascii, binary (base64), appended raw and base64,
                        each zlib-compressed or not, with UInt32 or UInt64
                        headers, Int32 or Int64 connectivity, Float32 or
                        Float64 points and arrays;
  pieces.pvtu           the mesh in 3 pieces (slabs in x), each with a
                        ghost layer (vtkGhostType) and GlobalNodeIds, the
                        points of each piece in another order, the shared
                        points of the last piece one float ulp away from
                        the others' (ids match them, coordinates would not);
  validation/fuzz/corpus/{vtu,msh}/
                        the fuzzers' seeds: the same formats for 8 points;
  cube-<version>.msh    Gmsh 4.1 and 2.2, ascii and binary, written by Gmsh
                        itself (python3-gmsh) with the field as $NodeData.

Every coordinate and value is a float32 number, so every encoding reads to
the same bits. Run from anywhere: python3 meshes/solver/make_fixtures.py
"""
import base64
import os
import struct
import sys
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
N = 7


def build_mesh(N=N):
    rng = np.random.default_rng(20261126)
    axis = np.linspace(0.0, 5.0, N)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    interior = np.all((points > 0) & (points < 5), axis=1)
    points[interior] += rng.uniform(-0.15, 0.15, size=(interior.sum(), 3))
    points = points.astype(np.float32).astype(np.float64)
    index = lambda i, j, k: (i * N + j) * N + k
    tets = []
    # Six tetrahedra around each cell's main diagonal (Kuhn), some in the
    # other orientation, which the reader must fix.
    paths = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(N - 1):
        for j in range(N - 1):
            for k in range(N - 1):
                for p in paths:
                    c = [i, j, k]
                    corners = [index(*c)]
                    for a in p:
                        c[a] += 1
                        corners.append(index(*c))
                    tets.append(corners)
    tets = np.array(tets, dtype=np.int64)
    distance = np.sqrt(((points - 2.5) ** 2).sum(axis=1)).astype(np.float32).astype(np.float64)
    return points, tets, distance


TYPES = {np.dtype(np.int32): "Int32", np.dtype(np.int64): "Int64", np.dtype(np.uint8): "UInt8",
         np.dtype(np.float32): "Float32", np.dtype(np.float64): "Float64", np.dtype(np.uint32): "UInt32",
         np.dtype(np.uint64): "UInt64"}


class Writer:
    """One VTK XML file: encoding 'ascii', 'binary', 'raw' or 'base64'
    (the last two appended), optionally compressed."""

    def __init__(self, encoding, compressed, header):
        self.encoding, self.compressed, self.header = encoding, compressed, header
        self.appended = b""

    def _header(self, values):
        return np.array(values, dtype=self.header).tobytes()

    def _blocks(self, data):
        """The header and data of one array, as VTK lays them out."""
        if not self.compressed:
            return self._header([len(data)]), data
        block = 1 << 12  # small blocks, so a fixture holds several
        chunks = [data[i:i + block] for i in range(0, len(data), block)] or [b""]
        packed = [zlib.compress(c) for c in chunks]
        last = len(chunks[-1]) if len(chunks[-1]) != block else 0
        return self._header([len(chunks), block, last] + [len(p) for p in packed]), b"".join(packed)

    def array(self, name, values, components=1, extra=""):
        values = np.ascontiguousarray(values)
        attrs = f'type="{TYPES[values.dtype]}" Name="{name}" NumberOfComponents="{components}"{extra}'
        if self.encoding == "ascii":
            text = " ".join(repr(float(v)) if values.dtype.kind == "f" else str(int(v)) for v in values.ravel())
            return f'<DataArray {attrs} format="ascii">\n{text}\n</DataArray>\n'
        header, data = self._blocks(values.tobytes())
        if self.encoding == "binary":
            text = (base64.b64encode(header) + base64.b64encode(data)).decode()
            return f'<DataArray {attrs} format="binary">\n{text}\n</DataArray>\n'
        offset = len(self.appended)
        if self.encoding == "raw":
            self.appended += header + data
        else:
            self.appended += base64.b64encode(header) + base64.b64encode(data)
        return f'<DataArray {attrs} format="appended" offset="{offset}"/>\n'

    def finish(self, body, kind="UnstructuredGrid"):
        compressor = ' compressor="vtkZLibDataCompressor"' if self.compressed else ""
        head = (f'<?xml version="1.0"?>\n<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" '
                f'header_type="{TYPES[np.dtype(self.header)]}"{compressor}>\n').encode()
        out = head + body.encode()
        if self.encoding in ("raw", "base64"):
            out += f'<AppendedData encoding="{self.encoding}">\n_'.encode() + self.appended + b"\n</AppendedData>\n"
        return out + b"</VTKFile>\n"


def write_vtu(path, w, points, tets, point_arrays, cell_arrays, conn_type, float_type, global_ids=None):
    types = np.full(len(tets), 10, dtype=np.uint8)
    offsets = (4 * np.arange(1, len(tets) + 1)).astype(conn_type)
    marks = f' GlobalIds="{global_ids}"' if global_ids else ""
    body = (f'<UnstructuredGrid>\n<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(tets)}">\n'
            f'<PointData Scalars="distance"{marks}>\n')
    for name, values in point_arrays:
        body += w.array(name, values.astype(float_type) if values.dtype.kind == "f" else values)
    body += "</PointData>\n<CellData>\n"
    for name, values in cell_arrays:
        body += w.array(name, values)
    body += "</CellData>\n<Points>\n" + w.array("Points", points.astype(float_type).ravel(), 3)
    body += "</Points>\n<Cells>\n"
    body += w.array("connectivity", tets.astype(conn_type).ravel())
    body += w.array("offsets", offsets)
    body += w.array("types", types)
    body += "</Cells>\n</Piece>\n</UnstructuredGrid>\n"
    with open(path, "wb") as f:
        f.write(w.finish(body))


ENCODINGS = [
    # name, encoding, compressed, header, connectivity, floats
    ("ascii", "ascii", False, np.uint32, np.int64, np.float64),
    ("binary", "binary", False, np.uint32, np.int32, np.float32),
    ("binary-zlib", "binary", True, np.uint32, np.int64, np.float64),
    ("binary-zlib-h64", "binary", True, np.uint64, np.int32, np.float32),
    ("raw", "raw", False, np.uint64, np.int64, np.float64),
    ("raw-h32", "raw", False, np.uint32, np.int32, np.float32),
    ("raw-zlib", "raw", True, np.uint32, np.int32, np.float64),
    ("raw-zlib-h64", "raw", True, np.uint64, np.int64, np.float32),
    ("base64", "base64", False, np.uint32, np.int64, np.float32),
    ("base64-zlib-h64", "base64", True, np.uint64, np.int32, np.float64),
]


def write_pieces(points, tets, distance, pieces=3):
    centroid_x = points[tets].mean(axis=1)[:, 0]
    owner = np.minimum((centroid_x / 5.0 * pieces).astype(int), pieces - 1)
    node_pieces = [set(tets[owner == p].ravel()) for p in range(pieces)]
    shared = set()
    for p in range(pieces):
        for q in range(p + 1, pieces):
            shared |= node_pieces[p] & node_pieces[q]
    sources = []
    for p in range(pieces):
        own = np.where(owner == p)[0]
        touching = np.where(np.isin(tets, list(node_pieces[p])).any(axis=1) & (owner != p))[0]
        cells = np.concatenate([own, touching])
        ghost = np.concatenate([np.zeros(len(own), np.uint8), np.ones(len(touching), np.uint8)])
        nodes = np.unique(tets[cells].ravel())
        if p % 2 == 1:
            nodes = nodes[::-1]  # another local order
        local = {g: i for i, g in enumerate(nodes)}
        piece_points = points[nodes].astype(np.float32)
        if p == pieces - 1:  # the same nodes, other coordinate bits
            for i, g in enumerate(nodes):
                if g in shared:
                    piece_points[i] = np.nextafter(piece_points[i], np.float32(10))
        piece_tets = np.vectorize(local.get)(tets[cells])
        w = Writer("raw", True, np.uint32) if p != 1 else Writer("binary", False, np.uint64)
        name = f"pieces_{p}.vtu"
        write_vtu(os.path.join(HERE, name), w, piece_points.astype(np.float64), piece_tets,
                  [("distance", distance[nodes]), ("GlobalNodeIds", nodes.astype(np.int64))],
                  [("vtkGhostType", ghost)], np.int64, np.float32, global_ids="GlobalNodeIds")
        sources.append(name)
    text = ('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt32">\n<PUnstructuredGrid GhostLevel="1">\n'
            '<PPointData Scalars="distance" GlobalIds="GlobalNodeIds">\n'
            '<PDataArray type="Float32" Name="distance"/>\n<PDataArray type="Int64" Name="GlobalNodeIds"/>\n'
            '</PPointData>\n<PCellData>\n<PDataArray type="UInt8" Name="vtkGhostType"/>\n</PCellData>\n'
            '<PPoints>\n<PDataArray type="Float32" NumberOfComponents="3"/>\n</PPoints>\n')
    text += "".join(f'<Piece Source="{s}"/>\n' for s in sources)
    text += "</PUnstructuredGrid>\n</VTKFile>\n"
    with open(os.path.join(HERE, "pieces.pvtu"), "w") as f:
        f.write(text)


def write_msh(points, tets, distance, directory=HERE, prefix="cube"):
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("cube")
    volume = gmsh.model.addDiscreteEntity(3)
    # Sparse tags: nodes numbered from 100 in steps of 3.
    tags = 100 + 3 * np.arange(len(points))
    gmsh.model.mesh.addNodes(3, volume, tags.tolist(), points.ravel().tolist())
    gmsh.model.mesh.addElementsByType(volume, 4, [], tags[tets].ravel().tolist())
    view = gmsh.view.add("distance")
    gmsh.view.addModelData(view, 0, "cube", "NodeData", tags.tolist(), distance.reshape(-1, 1).tolist())
    for version, binary in [(4.1, 0), (4.1, 1), (2.2, 0), (2.2, 1)]:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.option.setNumber("PostProcessing.SaveMesh", 0)
        name = os.path.join(directory, f"{prefix}-{version}{'-binary' if binary else ''}.msh")
        gmsh.write(name)
        gmsh.view.write(view, name, append=True)
    gmsh.finalize()


def write_fuzz_seeds():
    """Seed corpora of the fuzzers (validation/fuzz/corpus/): a 2x2x2
    lattice (6 tetrahedra) in every encoding and format."""
    corpus = os.path.join(HERE, "..", "..", "validation", "fuzz", "corpus")
    points, tets, distance = build_mesh(2)
    os.makedirs(os.path.join(corpus, "vtu"), exist_ok=True)
    os.makedirs(os.path.join(corpus, "msh"), exist_ok=True)
    for name, encoding, compressed, header, conn, floats in ENCODINGS:
        write_vtu(os.path.join(corpus, "vtu", f"{name}.vtu"), Writer(encoding, compressed, header), points, tets,
                  [("distance", distance), ("GlobalNodeIds", np.arange(len(points), dtype=np.int64))],
                  [("vtkGhostType", np.array([0, 0, 0, 0, 0, 1], np.uint8))], conn, floats,
                  global_ids="GlobalNodeIds")
    if "--no-msh" not in sys.argv:
        write_msh(points, tets, distance, os.path.join(corpus, "msh"), "seed")


def main():
    write_fuzz_seeds()
    points, tets, distance = build_mesh()
    for name, encoding, compressed, header, conn, floats in ENCODINGS:
        write_vtu(os.path.join(HERE, f"cube-{name}.vtu"), Writer(encoding, compressed, header), points, tets,
                  [("distance", distance)], [], conn, floats)
    write_pieces(points, tets, distance)
    if "--no-msh" not in sys.argv:
        write_msh(points, tets, distance)


if __name__ == "__main__":
    main()
