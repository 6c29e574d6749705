#!/usr/bin/python3
"""Writes a 10^6-node piece as ParaView writes large ones by default
(appended raw binary, UInt64 headers, Int64 connectivity and offsets,
Float64 points and field; --zlib: compressed) for tools/bench_read_vtu.sh.

Usage: bench_read_vtu.py OUT.vtu [N] [--zlib]   (N^3 nodes, default 100)
"""
import sys
import zlib

import numpy as np


def main():
    out = sys.argv[1]
    n = int(sys.argv[2]) if len(sys.argv) > 2 and sys.argv[2].isdigit() else 100
    compress = "--zlib" in sys.argv
    axis = np.linspace(0.0, 5.0, n)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    field = np.sqrt(((points - 2.5) ** 2).sum(axis=1))
    i, j, k = np.meshgrid(np.arange(n - 1), np.arange(n - 1), np.arange(n - 1), indexing="ij")
    base = ((i * n + j) * n + k).ravel()
    dx, dy, dz = n * n, n, 1
    tets = []
    for a, b in [(dx, dy), (dx, dz), (dy, dx), (dy, dz), (dz, dx), (dz, dy)]:
        tets.append(np.stack([base, base + a, base + a + b, base + dx + dy + dz], axis=1))
    tets = np.concatenate(tets).astype(np.int64)
    cells = len(tets)
    arrays = [("Points", points.ravel(), 3, "Float64", "Points"), ("distance", field, 1, "Float64", "PointData"),
              ("connectivity", tets.ravel(), 1, "Int64", "Cells"),
              ("offsets", 4 * np.arange(1, cells + 1, dtype=np.int64), 1, "Int64", "Cells"),
              ("types", np.full(cells, 10, np.uint8), 1, "UInt8", "Cells")]
    blob, tags = [], {}
    offset = 0
    for name, values, comps, kind, group in arrays:
        data = np.ascontiguousarray(values).tobytes()
        if compress:
            block = 1 << 15
            chunks = [data[p:p + block] for p in range(0, len(data), block)]
            packed = [zlib.compress(c, 1) for c in chunks]
            last = len(chunks[-1]) if len(chunks[-1]) != block else 0
            header = np.array([len(chunks), block, last] + [len(p) for p in packed], np.uint64).tobytes()
            data = b"".join(packed)
        else:
            header = np.array([len(data)], np.uint64).tobytes()
        tags.setdefault(group, []).append(
            f'<DataArray type="{kind}" Name="{name}" NumberOfComponents="{comps}" format="appended" offset="{offset}"/>')
        blob += [header, data]
        offset += len(header) + len(data)
    compressor = ' compressor="vtkZLibDataCompressor"' if compress else ""
    head = (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            f'header_type="UInt64"{compressor}>\n<UnstructuredGrid>\n'
            f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{cells}">\n'
            f'<PointData Scalars="distance">{"".join(tags["PointData"])}</PointData>\n'
            f'<Points>{"".join(tags["Points"])}</Points>\n<Cells>{"".join(tags["Cells"])}</Cells>\n'
            '</Piece>\n</UnstructuredGrid>\n<AppendedData encoding="raw">\n_')
    with open(out, "wb") as f:
        f.write(head.encode())
        for b in blob:
            f.write(b)
        f.write(b"\n</AppendedData>\n</VTKFile>\n")


if __name__ == "__main__":
    main()
