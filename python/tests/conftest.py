"""Shared fixtures: the `tetiso` command the module is compared against, the
repository's meshes, and a reader of the ASCII .vtu fixture as arrays."""
import os
import pathlib
import subprocess
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("TETISO_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture(scope="session")
def cli():
    """Runs `tetiso ARGS...`; returns the finished process (stdout, stderr as text)."""
    program = os.environ.get("TETISO_CLI")
    if not program or not os.path.exists(program):
        pytest.skip("TETISO_CLI names no tetiso program (ctest sets it)")

    def run(*args, check=True):
        done = subprocess.run([program, *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"tetiso {' '.join(map(str, args))}: status {done.returncode}: {done.stderr}")
        return done

    return run


def read_ascii_vtu(path, array):
    """Points (n, 3) float64, tetrahedra (m, 4) int64 and one point array of an
    ASCII .vtu of tetrahedra (the meshes/solver fixtures)."""
    root = ElementTree.parse(path).getroot()
    arrays = {a.get("Name"): np.array(a.text.split(), dtype=float) for a in root.iter("DataArray")}
    types = arrays["types"]
    assert (types == 10).all(), "a fixture of tetrahedra only"
    return arrays["Points"].reshape(-1, 3), arrays["connectivity"].astype(np.int64).reshape(-1, 4), arrays[array]


@pytest.fixture(scope="session")
def cube_vtu():
    path = SOURCE_DIR / "meshes" / "solver" / "cube-ascii.vtu"
    points, tets, distance = read_ascii_vtu(path, "distance")
    return path, points, tets, distance
