"""Each call gives the bytes of the command it mirrors, on the same input:
the module and the CLI are one library, and defaults are the CLI's."""
import json

import numpy as np
import pytest

import tetiso


def same_file(a, b):
    return a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize("reduce", [False, True])
def test_extract_from_arrays_is_extract_of_the_mesh_file(cli, cube_vtu, tmp_path, reduce):
    path, points, tets, distance = cube_vtu
    flags = ["--reduce"] if reduce else []
    cli("extract", "--mesh", path, "--array", "distance", "--level", 2.1, *flags, "-o", tmp_path / "cli.ply")
    surface = tetiso.extract(points, tets, distance, 2.1, reduce=reduce)
    surface.write(tmp_path / "module.ply")
    assert surface.triangle_count > 0
    assert same_file(tmp_path / "cli.ply", tmp_path / "module.ply")


def test_extract_with_a_named_field_evaluates_it_at_the_points(cli, cube_vtu, tmp_path):
    path, points, tets, _ = cube_vtu
    cli("extract", "--mesh", path, "--field", "sphere", "-o", tmp_path / "cli.vtp")
    tetiso.extract(points, tets, "sphere").write(tmp_path / "module.vtp")
    assert same_file(tmp_path / "cli.vtp", tmp_path / "module.vtp")


def test_extract_lattice_is_extract_lattice(cli, tmp_path):
    cli("extract", "--lattice", 20, "--domains", 3, "--field", "torus", "--reduce", "--phi", 0.8,
        "--max-error", 0.3, "--threads", 2, "-o", tmp_path / "cli.ply")
    surface = tetiso.extract_lattice(20, domains=3, field="torus", reduce=True, phi=0.8, max_error=0.3, threads=2)
    surface.write(tmp_path / "module.ply")
    assert same_file(tmp_path / "cli.ply", tmp_path / "module.ply")


def test_reduce_is_reduce(cli, tmp_path):
    cli("extract", "--lattice", 24, "-o", tmp_path / "raw.ply")
    cli("reduce", tmp_path / "raw.ply", "-o", tmp_path / "cli.ply")
    raw = tetiso.read(tmp_path / "raw.ply")
    reduced = tetiso.reduce(raw)
    reduced.write(tmp_path / "module.ply")
    assert reduced.triangle_count < raw.triangle_count
    assert same_file(tmp_path / "cli.ply", tmp_path / "module.ply")


def test_seaming_the_lattice_pieces_is_the_run_jobs_surface(cli, tmp_path):
    cli("run", "--lattice", 24, "--domains", 2, "--threads", 1, "--quiet", "-o", tmp_path / "cli.ply")
    lattice = tetiso.Lattice(24, 2)
    a, b = lattice.piece(0), lattice.piece(1)
    assert (a.flags & 1).any() and a.sample_count > 0, "interface vertices locked, raw vertices kept for the seam"
    surface = tetiso.seam(a, b, lattice=lattice, max_error=0.25 * lattice.spacing)
    surface.write(tmp_path / "module.ply")
    assert not (surface.flags & 1).any(), "the last seam settles every vertex"
    assert same_file(tmp_path / "cli.ply", tmp_path / "module.ply")


def test_merging_pieces_is_extracting_the_whole(tmp_path):
    lattice = tetiso.Lattice(16, 4, "gyroid")
    pieces = [lattice.piece(d, reduce=False) for d in range(lattice.domain_count)]
    merged = tetiso.merge(pieces[::-1])
    whole = tetiso.extract_lattice(16, field="gyroid")
    merged.write(tmp_path / "merged.ply")
    whole.write(tmp_path / "whole.ply")
    # extract_lattice also unlocks what is settled; the geometry and keys are the same.
    assert np.array_equal(merged.keys, whole.keys) and np.array_equal(merged.triangles, whole.triangles)
    assert np.array_equal(merged.x, whole.x) and np.array_equal(merged.z, whole.z)


def cli_check(cli, path, *flags):
    done = cli("check", path, *flags, check=False)
    report = json.loads(done.stdout)
    report.pop("file", None)
    if "against" in report:
        report["against"].pop("file", None)
    return done, report


def test_check_reports_what_the_cli_reports(cli, tmp_path):
    cli("extract", "--lattice", 16, "-o", tmp_path / "raw.ply")
    cli("reduce", tmp_path / "raw.ply", "-o", tmp_path / "reduced.ply")
    done, expected = cli_check(cli, tmp_path / "reduced.ply", "--against", tmp_path / "raw.ply", "--strict")
    assert done.returncode == 0
    report = tetiso.check(tetiso.read(tmp_path / "reduced.ply"), against=tetiso.read(tmp_path / "raw.ply"), strict=True)
    assert report == expected
    assert report["violations"] == [] and report["against"]["same_signatures"]


def test_a_broken_surface_gets_the_clis_verdicts(cli, tmp_path):
    clean = tetiso.extract_lattice(12)
    triangles = clean.triangles.copy()
    triangles[5] = triangles[5][::-1]                    # one triangle turned over
    triangles = np.vstack([triangles, triangles[:1]])    # and one listed twice
    broken = tetiso.Surface(clean.points, triangles, keys=clean.keys)
    broken.write(tmp_path / "broken.ply")
    done, expected = cli_check(cli, tmp_path / "broken.ply", "--strict")
    report = tetiso.check(broken, strict=True)
    assert done.returncode == 1
    prefix = f"tetiso check: {tmp_path / 'broken.ply'}: "
    cli_lines = [line.removeprefix(prefix) for line in done.stderr.splitlines()]
    assert report["violations"] == cli_lines == expected["violations"]
    assert any(line.startswith("orientation: ") for line in cli_lines)
    assert any(line.startswith("duplicate triangles: ") for line in cli_lines)
    assert report == expected


@pytest.mark.parametrize("call, cli_args, message", [
    (lambda: tetiso.extract_lattice(10, field="x+"), ["--field", "x+"],
     "field 'x+' is neither a built-in (paper, sphere, torus, gyroid) nor an expression in x, y, z that parses: "
     "Unexpected end of expression at position 3"),
    (lambda: tetiso.extract_lattice(1), ["--domains", "1"], None),
])
def test_library_errors_have_the_clis_message(cli, tmp_path, call, cli_args, message):
    lattice = "1" if message is None else "10"
    done = cli("extract", "--lattice", lattice, *cli_args, "-o", tmp_path / "x.ply", check=False)
    with pytest.raises(tetiso.Error) as raised:
        call()
    if message is None:   # the CLI refuses --lattice 1 while parsing; the library says why itself
        assert done.returncode == 2 and "lattice" in str(raised.value)
    else:
        assert done.returncode == 2 and done.stderr.strip() == "tetiso: " + message == "tetiso: " + str(raised.value)


@pytest.mark.parametrize("keyword, value, cli_option, cli_value", [
    ("phi", 0.0, "--phi", "0"),
    ("threads", 5000, "--threads", "5000"),
    ("max_error", -1.0, "--max-error", "-1"),
    ("level", float("nan"), "--level", "nan"),
])
def test_options_are_refused_in_the_clis_words(cli, tmp_path, keyword, value, cli_option, cli_value):
    done = cli("extract", "--lattice", 10, cli_option, cli_value, "-o", tmp_path / "x.ply", check=False)
    with pytest.raises(tetiso.Error) as raised:
        tetiso.extract_lattice(10, **{keyword: value})
    # "tetiso: --phi: 0 is outside (0, 1] (see tetiso --help)" against "phi: 0 is outside (0, 1]"
    cli_message = done.stderr.strip().removeprefix("tetiso: ").removesuffix(" (see tetiso --help)")
    assert cli_message == "--" + str(raised.value).replace("_", "-", 1 if keyword == "max_error" else 0)


def test_a_missing_file_is_named_as_the_cli_names_it(cli, tmp_path):
    done = cli("reduce", tmp_path / "none.ply", "-o", tmp_path / "out.ply", check=False)
    with pytest.raises(tetiso.Error) as raised:
        tetiso.read(tmp_path / "none.ply")
    assert done.returncode == 2 and done.stderr.strip() == "tetiso: " + str(raised.value)


def test_devices_are_refused_as_the_cli_refuses_them(cli, tmp_path):
    done = cli("extract", "--lattice", 8, "--device", "gpu", "-o", tmp_path / "x.ply", check=False)
    if done.returncode == 0:
        pytest.skip("this machine has a GPU")
    with pytest.raises(tetiso.Error) as raised:
        tetiso.extract_lattice(8, device="gpu")
    assert done.stderr.strip() == "tetiso: --" + str(raised.value)     # "--device gpu: <why there is none>"
    with pytest.raises(tetiso.Error, match=r"^device: 'tpu' is neither 'cpu' nor 'gpu'$"):
        tetiso.extract_lattice(8, device="tpu")
    with pytest.raises(tetiso.Error, match=r"^gpu: applies with device='gpu'; the work runs on the CPU$"):
        tetiso.extract_lattice(8, gpu=1)


def test_a_seam_asks_a_python_function_which_domains_hold_an_edge():
    lattice = tetiso.Lattice(20, 4)
    a, b = lattice.piece(0), lattice.piece(1)
    asked = []

    def holders(low, high):
        asked.append((low, high))
        return lattice.domains_of_edge(low, high)

    by_lattice = tetiso.seam(a, b, lattice=lattice, max_error=0.25 * lattice.spacing)
    by_function = tetiso.seam(a, b, domains_of_edge=holders, max_error=0.25 * lattice.spacing)
    assert asked and all(np.array_equal(getattr(by_lattice, name), getattr(by_function, name))
                         for name in ("x", "y", "z", "keys", "flags", "triangles", "error"))
    assert (by_lattice.flags & 1).any(), "edges shared with domains 2 and 3 stay locked"
    settled_all = tetiso.seam(a, b, max_error=0.25 * lattice.spacing)    # neither: the last seam
    assert not (settled_all.flags & 1).any()

    def broken(low, high):
        raise ValueError(f"no holders for {low}-{high}")
    with pytest.raises(ValueError, match="^no holders for"):
        tetiso.seam(a, b, domains_of_edge=broken)
    with pytest.raises(tetiso.Error, match="^seam: give lattice or domains_of_edge, not both$"):
        tetiso.seam(a, b, lattice=lattice, domains_of_edge=holders)
