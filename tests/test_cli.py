"""The command line: outputs of `pinbore mesh` and `pinbore fem`, bad input, early stops."""

import json

import gmsh
import pytest
from conftest import ROOT, pinbore, scene_dict

from pinbore.fem import curve as fe_curve
from pinbore.meshes.model import (BORE_SURFACE, HOUSING, HOUSING_EDGE, HOUSING_ENDS, HUB, PIN, PIN_ENDS,
                          PIN_SURFACE, SYMMETRY)


def test_fem_writes_curve_pressure_result_fields_picture(write_scene, tmp_path):
    data = scene_dict(output={"fields": True, "picture": True})
    out = tmp_path / "run"
    done = pinbore("fem", write_scene(data), "--out", out, process=True)   # the command itself
    assert done.returncode == 0, done.stderr
    names = {p.name for p in out.iterdir()}
    assert {"curve.csv", "pressure.csv", "result.json", "fields.xdmf", "fields.h5",
            "contact.png"} <= names
    curve = fe_curve.read(out / "curve.csv")   # a 2D curve: forces per unit length
    assert curve.dim == 2 and curve.points == data["load"]["steps"]
    assert "force_per_length_N_per_m" in (out / "curve.csv").read_text().splitlines()[0]
    assert all(curve.force > 0) and list(curve.force) == sorted(curve.force)
    pressure = fe_curve.read_pressure(out / "pressure.csv")
    assert pressure.dim == 2 and pressure.z is None and pressure.shear_axial is None
    assert set(pressure.state) <= {"open", "slip"}  # frictionless: no stick
    result = json.loads((out / "result.json").read_text())
    assert result["status"] == "complete" and result["dofs"] > 0
    assert result["scene"]["geometry"]["pin_radius"] == data["geometry"]["pin_radius"]
    assert len(result["snes_reasons"]) == curve.points
    assert not list(tmp_path.glob(".run.*"))  # no temporary directory left


@pytest.mark.parametrize("dim", [2, 3])
def test_mesh_has_every_physical_group(write_scene, tmp_path, dim):
    data = scene_dict(geometry={"dim": dim, "length": 0.02}, mesh={"layers": 3} if dim == 3 else {})
    out = tmp_path / "mesh"
    done = pinbore("mesh", write_scene(data), "--out", out)
    assert done.returncode == 0, done.stderr
    assert (out / "preview.png").stat().st_size > 10_000
    gmsh.initialize(interruptible=False)
    try:
        gmsh.open(str(out / "mesh.msh"))
        groups = set(gmsh.model.getPhysicalGroups())
    finally:
        gmsh.finalize()
    expected = {(dim, PIN), (dim, HOUSING), (dim - 1, HUB), (dim - 1, PIN_SURFACE),
                (dim - 1, BORE_SURFACE), (dim - 1, HOUSING_EDGE)}
    if dim == 3:   # a half model: the ends z = 0 and the mid-plane
        expected |= {(2, PIN_ENDS), (2, HOUSING_ENDS), (2, SYMMETRY)}
    assert groups == expected


BAD = [
    ("geometry", "pin_radius", 10.0e-3, "bore_radius must exceed pin_radius"),
    ("geometry", "hub_radius", 9.99e-3, "hub_radius must be smaller than pin_radius"),
    ("geometry", "housing_radius", 10.0e-3, "housing_radius must exceed bore_radius"),
    ("materials.pin", "E", -1.0, "materials.pin.E"),
    ("materials.bore", "nu", 0.5, "materials.bore.nu"),
    ("materials.pin", "nu", -1.0, "materials.pin.nu"),
    ("load", "steps", 0, "load.steps"),
    ("contact", "method", "lagrange", "contact.method"),
    ("contact", "friction", -0.1, "contact.friction"),
    ("load", "max_approach", "1e-5", "load.max_approach"),
    ("load", "first_approach", 2e-5, "first_approach must be below max_approach"),
]


BAD_LOADS = [
    ({"max_approach": 0.0, "rotation_deg": 0.05}, "rotation_deg needs a radial push first"),
    ({"tangential_push": 1e-6, "rotation_deg": 0.05}, "not rotation_deg and tangential_push"),
    ({"tilt_deg": 0.05, "rotation_deg": 0.05}, "not rotation_deg and tilt_deg"),
    ({"tilt_deg": 0.05}, "load.tilt_deg applies to dim = 3 only"),
    ({"rotation_deg": 5.0}, "load.rotation_deg: |rotation| must be <="),
    ({"rotation_deg": 0.0}, "rotation_deg must not be 0"),
]


BAD_3D = [
    ({"length": 0.0}, {}, "geometry.length"),
    ({"length": 0.02, "tilt_deg": 0.1}, {}, "the tilted pin's end reaches"),
    ({"length": 0.02, "tilt_deg": 0.02}, {"symmetry": True}, "mesh.symmetry: a tilted pin"),
    ({"length": 0.02, "relief_length": 1e-3}, {}, "relief_length and relief_depth go together"),
    ({"length": 0.02}, {"symmetry": True, "load": {"tilt_deg": 0.05}},
     "mesh.symmetry: a tilt load is not symmetric"),
    ({"length": 0.02}, {"load": {"tilt_deg": 1.0}}, "load.tilt_deg: |tilt| must be <= 0.254 deg"),
    ({"length": 0.02}, {"load": {"tilt_deg": -50.0}}, "load.tilt_deg: the tilt pushes the pin's end"),
]


@pytest.mark.parametrize("geometry, mesh, message", BAD_3D)
def test_bad_3d_geometry_is_one_line_exit_2(write_scene, tmp_path, geometry, mesh, message):
    mesh = dict(mesh)
    data = scene_dict(geometry={"dim": 3} | geometry, mesh=mesh, load=mesh.pop("load", {}))
    done = pinbore("fem", write_scene(data), "--out", tmp_path / "out")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1


def test_3d_options_in_a_2d_scene_are_refused(write_scene, tmp_path):
    done = pinbore("fem", write_scene(scene_dict(geometry={"tilt_deg": 0.01})), "--out",
                   tmp_path / "out")
    assert done.returncode == 2 and "tilt_deg applies to dim = 3 only" in done.stderr


@pytest.mark.parametrize("load, message", BAD_LOADS)
def test_bad_load_programme_is_one_line_exit_2(write_scene, tmp_path, load, message):
    done = pinbore("fem", write_scene(scene_dict(load=load)), "--out", tmp_path / "out")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("table, key, value, message", BAD)
def test_bad_value_is_one_line_exit_2_nothing_written(write_scene, tmp_path, table, key, value,
                                                      message):
    data = scene_dict()
    section = data
    for part in table.split("."):
        section = section[part]
    section[key] = value
    out = tmp_path / "out"
    done = pinbore("fem", write_scene(data), "--out", out)
    assert done.returncode == 2
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert "Traceback" not in done.stderr
    assert not out.exists() and not list(tmp_path.glob(".out*"))


def test_missing_and_unknown_keys(write_scene, tmp_path):
    data = scene_dict()
    del data["load"]["steps"]
    done = pinbore("fem", write_scene(data), "--out", tmp_path / "out")
    assert done.returncode == 2 and "load.steps: required key is missing" in done.stderr
    data = scene_dict(contact={"stiffness": 1.0})
    done = pinbore("fem", write_scene(data), "--out", tmp_path / "out")
    assert done.returncode == 2 and "contact.stiffness: unknown key" in done.stderr


def test_unreadable_and_malformed_files(write_scene, tmp_path):
    done = pinbore("fem", tmp_path / "absent.toml", "--out", tmp_path / "out")
    assert done.returncode == 2 and "cannot read scene file" in done.stderr
    done = pinbore("mesh", write_scene("kind = \n"), "--out", tmp_path / "out")
    assert done.returncode == 2 and "not valid TOML" in done.stderr
    assert not (tmp_path / "out").exists()


def test_a_run_that_cannot_converge_keeps_what_converged_and_says_so(write_scene, tmp_path):
    # One Newton iteration per solve cannot follow the contact: the first step fails at every
    # cutback. The run must stop, say where and why, and leave a marked, complete output.
    data = scene_dict(solver={"newton_max_it": 1, "max_cutbacks": 2})
    out = tmp_path / "out"
    done = pinbore("fem", write_scene(data), "--out", out)
    assert done.returncode == 1
    assert "stopped early" in done.stderr and "DIVERGED_MAX_IT" in done.stderr
    result = json.loads((out / "result.json").read_text())
    assert result["status"] == "incomplete" and result["cutbacks"] == 3
    assert "gave up after 2 cutbacks" in result["stop"]["message"]
    assert fe_curve.read(out / "curve.csv").points == result["steps_converged"]


def test_help_lists_every_command():
    done = pinbore("--help", process=True)
    assert done.returncode == 0
    for command in ("mesh", "fem", "report"):
        assert command in done.stdout
        assert pinbore(command, "--help").returncode == 0


def test_every_shipped_scene_is_valid():
    from pinbore.fem.scene import FemScene
    from pinbore.core import scene

    paths = sorted((ROOT / "scenes" / "fem").glob("*.toml"))
    assert paths
    for path in paths:
        scene.load(FemScene, path)


def test_version_is_the_packages():
    """`pinbore --version` prints the installed package's version, that of pyproject.toml."""
    import tomllib

    done = pinbore("--version")
    expected = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert done.returncode == 0 and done.stdout.strip() == f"pinbore {expected}"


def test_the_lock_satisfies_the_stated_ranges():
    """pyproject.toml states ranges, requirements.lock exact versions: each locked direct
    dependency lies in its range (pip's own check of the environment built from the lock)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "pip", "check"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
