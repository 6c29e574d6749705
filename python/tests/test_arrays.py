"""NumPy in and out: which dtypes and layouts are taken (and give the same
surface), which are refused and how, and that results are views, not copies."""
import gc
import threading
import time

import numpy as np
import pytest

import tetiso


@pytest.fixture(scope="module")
def mesh(cube_vtu):
    _, points, tets, distance = cube_vtu
    return points, tets, distance


def same_surface(a, b):
    return all(np.array_equal(getattr(a, name), getattr(b, name)) for name in ("x", "y", "z", "keys", "flags", "triangles"))


def test_any_float_dtype_layout_and_byte_order_gives_the_same_surface(mesh):
    points, tets, distance = mesh
    reference = tetiso.extract(points, tets, distance, 2.1)
    fortran_points = np.asfortranarray(points)
    strided = np.zeros((len(points), 6))[:, ::2]
    strided[:] = points
    big_endian = points.astype(">f8")
    for variant in (fortran_points, strided, big_endian, points.astype(np.float32)):
        # float32 is exact here: the fixture's coordinates are floats written in full
        surface = tetiso.extract(variant, tets.astype(np.int32), distance[::-1].copy()[::-1], 2.1)
        assert same_surface(surface, reference)
    assert same_surface(tetiso.extract(points, tets.astype(np.uint16), distance.astype(np.float32), 2.1), reference)


def with_value(array, flat_index, value):
    """A copy of `array` with element `flat_index` (in row order) set to `value`."""
    changed = array.astype(float if np.isnan(value) or abs(value) > 1e30 else array.dtype)
    changed.reshape(-1)[flat_index] = value
    return changed


@pytest.mark.parametrize("change, message", [
    (dict(points=lambda p: p.astype(np.int64)),
     "extract: points: expected floating-point values (float32 or float64), not int64 of shape (343, 3)"),
    (dict(points=lambda p: p[:, :2]),
     "extract: points: expected floating-point values (float32 or float64) of shape (n, 3), not float64 of shape (343, 2)"),
    (dict(tets=lambda t: t.astype(float)), "extract: tets: expected integers, not float64 of shape (1296, 4)"),
    (dict(field=lambda f: f[:-1]), "extract: field: expected 343 rows (one per point), not 342"),
    (dict(field=lambda f: f.astype(complex)),
     "extract: field: expected floating-point values (float32 or float64), not complex128 of shape (343,)"),
    (dict(tets=lambda t: with_value(t, 700, 343)), "domain 0: tetrahedron 175 refers to a node that does not exist"),
    (dict(tets=lambda t: with_value(t, 9, -1)), "domain 0: tetrahedron 2 refers to a node that does not exist"),
    (dict(points=lambda p: with_value(p, 60, np.nan)),
     "extract: points: node 20 has a coordinate that is not finite (as a float)"),
    (dict(points=lambda p: with_value(p, 61, 1e39)),
     "extract: points: node 20 has a coordinate that is not finite (as a float)"),
    (dict(field=lambda f: with_value(f, 17, np.inf)), "domain 0: node 17 has a field value that is not finite"),
    (dict(points=lambda p: "points"), "extract: points: expected floating-point values (float32 or float64), not <U6 of shape ()"),
])
def test_refused_arrays_are_named_with_what_is_wrong(mesh, change, message):
    arrays = dict(zip(("points", "tets", "field"), mesh))
    for name, transform in change.items():
        arrays[name] = transform(arrays[name])
    with pytest.raises(tetiso.Error) as raised:
        tetiso.extract(arrays["points"], arrays["tets"], arrays["field"], 2.1)
    assert str(raised.value) == message


def test_a_tetrahedron_of_zero_volume_is_refused_and_the_others_are_oriented(mesh):
    points, tets, distance = mesh
    flipped = tets.copy()
    flipped[:, [2, 3]] = flipped[:, [3, 2]]
    assert same_surface(tetiso.extract(points, flipped, distance, 2.1), tetiso.extract(points, tets, distance, 2.1))
    flat = tets.copy()
    flat[3] = [0, 1, 2, 3]      # four points on one lattice line
    with pytest.raises(tetiso.Error, match=r"^extract: tets: tetrahedron 3 has zero volume"):
        tetiso.extract(points, flat, distance, 2.1)


def test_node_ids_make_the_keys(mesh):
    points, tets, distance = mesh
    ids = np.arange(len(points), dtype=np.int64) * 3 + 1000
    surface = tetiso.extract(points, tets, distance, 2.1, node_ids=ids)
    plain = tetiso.extract(points, tets, distance, 2.1)
    low, high = plain.keys >> np.uint64(32), plain.keys & np.uint64(0xFFFFFFFF)
    expected = ((low * np.uint64(3) + np.uint64(1000)) << np.uint64(32)) | (high * np.uint64(3) + np.uint64(1000))
    assert np.array_equal(surface.keys, expected)
    with pytest.raises(tetiso.Error, match="node id 1000 appears more than once"):
        tetiso.extract(points, tets, distance, 2.1, node_ids=np.full(len(points), 1000))
    with pytest.raises(tetiso.Error, match=r"extract: node_ids: value -1 at position 0 is outside \[0, 4294967295\]"):
        tetiso.extract(points, tets, distance, 2.1, node_ids=ids - 1001)


def test_interface_nodes_lock_their_vertices(mesh):
    points, tets, distance = mesh
    on_plane = (points[:, 0] == 0).astype(np.uint8)      # the x = 0 face as an interface
    surface = tetiso.extract(points, tets, distance, 3.0, interface=on_plane)   # a level that reaches it
    locked = (surface.flags & 1).astype(bool)
    assert locked.any() and np.all(surface.x[locked] == 0)
    reduced = tetiso.reduce(surface)
    kept = np.isin(surface.keys[locked], reduced.keys)
    assert kept.all(), "a reduction neither moves nor removes a locked vertex"


def test_results_are_read_only_views_that_keep_the_surface_alive():
    surface = tetiso.extract_lattice(12)
    x = surface.x
    assert np.shares_memory(x, surface.x) and x.ctypes.data == surface.x.ctypes.data
    assert x.dtype == np.float32 and surface.keys.dtype == np.uint64 and surface.triangles.dtype == np.int32
    assert surface.triangles.shape == (surface.triangle_count, 3) and surface.triangles.flags.c_contiguous
    with pytest.raises(ValueError, match="read-only"):
        x[0] = 1
    points = surface.points
    assert points.shape == (surface.vertex_count, 3) and not np.shares_memory(points, x), "points is the one copy"
    first = float(x[0])
    triangles = surface.triangles
    del surface
    gc.collect()
    tetiso.extract_lattice(12, field="sphere")    # reuses freed memory, if any was freed
    assert float(x[0]) == first and triangles.max() < len(x)


def test_a_surface_from_arrays_is_ordered_by_key():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    surface = tetiso.Surface(points, [[0, 1, 2]], keys=np.array([30, 10, 20], dtype=np.uint64))
    assert list(surface.keys) == [10, 20, 30]
    assert np.array_equal(surface.points[surface.triangles[0]], points)
    with pytest.raises(tetiso.Error, match="^Surface: keys: two vertices have the same key$"):
        tetiso.Surface(points, [[0, 1, 2]], keys=[1, 1, 2])
    with pytest.raises(tetiso.Error, match=r"^Surface: triangles: value 3 at row 0, column 2 is outside \[0, 2\]$"):
        tetiso.Surface(points, [[0, 1, 3]])


def test_the_gil_is_released_while_the_library_works():
    surface = tetiso.extract_lattice(60)
    span = {}

    def work():
        span["start"] = time.monotonic()
        tetiso.reduce(surface)
        span["end"] = time.monotonic()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.monotonic())
        time.sleep(0.001)
    worker.join()
    start, end = span["start"], span["end"]
    middle = [t for t in ticks if start + 0.25 * (end - start) < t < end - 0.25 * (end - start)]
    # Holding the GIL for the call, the reduction would let this thread run no
    # Python at all between the call's start and its end.
    assert end - start > 0.05 and len(middle) >= 3, (end - start, len(middle))
