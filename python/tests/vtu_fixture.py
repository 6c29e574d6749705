"""ASCII .vtu files of tetrahedra, read and written with NumPy alone: the
meshes/solver fixture as arrays, and pieces written as a .pvtu for the CLI to
read what the in-situ call was given."""
import xml.etree.ElementTree as ElementTree

import numpy as np

VTK_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.int64): "Int64", np.dtype(np.uint8): "UInt8"}


def read_ascii_vtu(path, array):
    """Points (n, 3) float64, tetrahedra (m, 4) int64 and one point array."""
    root = ElementTree.parse(path).getroot()
    arrays = {a.get("Name"): np.array(a.text.split(), dtype=float) for a in root.iter("DataArray")}
    assert (arrays["types"] == 10).all(), "a fixture of tetrahedra only"
    return arrays["Points"].reshape(-1, 3), arrays["connectivity"].astype(np.int64).reshape(-1, 4), arrays[array]


def data_array(name, values, components=1):
    values = np.asarray(values)
    text = " ".join(repr(float(v)) if values.dtype.kind == "f" else str(int(v)) for v in values.ravel())
    return (f'<DataArray type="{VTK_TYPES[values.dtype]}" Name="{name}" NumberOfComponents="{components}" '
            f'format="ascii">\n{text}\n</DataArray>\n')


def write_ascii_vtu(path, points, tets, point_arrays, ghost_cells):
    """One piece: point_arrays maps a name to one value per point; global node
    ids are the array named GlobalNodeIds."""
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
                  'header_type="UInt32">\n<UnstructuredGrid>\n'
                  f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(tets)}">\n'
                  '<PointData GlobalIds="GlobalNodeIds">\n')
        for name, values in point_arrays.items():
            out.write(data_array(name, values))
        out.write("</PointData>\n<CellData>\n" + data_array("vtkGhostType", ghost_cells.astype(np.uint8)) +
                  "</CellData>\n<Points>\n" + data_array("Points", points.astype(np.float64), 3) +
                  "</Points>\n<Cells>\n" + data_array("connectivity", tets.astype(np.int64)) +
                  data_array("offsets", np.arange(4, 4 * len(tets) + 1, 4, dtype=np.int64)) +
                  data_array("types", np.full(len(tets), 10, np.uint8)) +
                  "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")


def write_pvtu(path, piece_names, point_arrays):
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian" '
                  'header_type="UInt32">\n<PUnstructuredGrid GhostLevel="1">\n<PPointData GlobalIds="GlobalNodeIds">\n')
        for name, dtype in point_arrays.items():
            out.write(f'<PDataArray type="{VTK_TYPES[np.dtype(dtype)]}" Name="{name}"/>\n')
        out.write('</PPointData>\n<PCellData>\n<PDataArray type="UInt8" Name="vtkGhostType"/>\n</PCellData>\n'
                  '<PPoints>\n<PDataArray type="Float64" NumberOfComponents="3"/>\n</PPoints>\n')
        for name in piece_names:
            out.write(f'<Piece Source="{name}"/>\n')
        out.write("</PUnstructuredGrid>\n</VTKFile>\n")
