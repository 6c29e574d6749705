"""Shared fixtures: the `tetiso` command the module is compared against, the
repository's meshes, and the ASCII .vtu fixture as arrays."""
import os
import pathlib
import subprocess

import pytest

from vtu_fixture import read_ascii_vtu

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


@pytest.fixture(scope="session")
def cube_vtu():
    path = SOURCE_DIR / "meshes" / "solver" / "cube-ascii.vtu"
    points, tets, distance = read_ascii_vtu(path, "distance")
    return path, points, tets, distance
