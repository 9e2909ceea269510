"""Bad input in every command: one line naming the key (or option) and the rule, exit code 2,
nothing written. One table per class of fault, so a class cannot come back."""

import copy
import json
import math
import tomllib

import pytest
from conftest import ROOT, pinbore, scene_dict

INF, NAN = math.inf, math.nan
FLORES = tomllib.loads((ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml").read_text())


def fem_with(**tables):
    return scene_dict(**tables)


def reduced_with(edit):
    data = copy.deepcopy(FLORES)
    edit(data)
    return data


def expect_one_line(done, message, out):
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], done.stderr
    assert not out.exists() and not list(out.parent.glob(f".{out.name}*"))


# numbers that are not finite, wherever a scene reads a float
NOT_FINITE = [
    ("mesh", fem_with(geometry={"housing_radius": INF}), "geometry.housing_radius: Input should be a finite number"),
    ("fem", fem_with(materials={"pin": {"E": NAN, "nu": 0.3}}), "materials.pin.E: Input should be a finite number"),
    ("fem", fem_with(load={"max_approach": INF}), "load.max_approach: Input should be a finite number"),
    ("reduced", reduced_with(lambda d: d.update(duration=INF)), "duration: Input should be a finite number"),
    ("reduced", reduced_with(lambda d: d["bodies"][0].update(mass=INF)), "bodies.0.mass: Input should be a finite number"),
    ("reduced", reduced_with(lambda d: d["bodies"][1].update(inertia=INF)), "bodies.1.inertia: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d["bodies"][1].update(angle_deg=NAN)), "bodies.1.angle_deg: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d["bodies"][2].update(position=[0.0, INF])), "bodies.2.position.1: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d["drive"].update(speed_rpm=NAN)), "drive.speed_rpm: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d.update(gravity=[0.0, -INF])), "gravity.1: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d["clearance_joints"][0].update(E=INF)), "clearance_joints.0.E: Input should be a finite"),
    ("reduced", reduced_with(lambda d: d["clearance_joints"][0].update(bearing_point=[NAN, 0.0])),
     "clearance_joints.0.bearing_point.0: Input should be a finite"),
]

# keys that name the wrong thing or do not apply
MISPLACED = [
    ("mesh", fem_with(mesh={"layers": 8}), "mesh.layers applies to dim = 3 only"),
    ("fem", fem_with(mesh={"symmetry": True}), "mesh.symmetry applies to dim = 3 only"),
    ("reduced", reduced_with(lambda d: d["drive"].update(body="ground")), "drive.body: must be a moving body"),
    ("reduced", reduced_with(lambda d: d["clearance_joints"][0].update(friction={
        "law": "lugre", "mu_coulomb": 0.0, "mu_static": 0.0, "stribeck_speed": 0.01, "sigma0": 1e5})),
     "clearance_joints.0.friction.lugre.mu_coulomb: Input should be greater than 0"),
    ("reduced", reduced_with(lambda d: d["integrator"].update(fixed_step=1e-6)),
     "integrator: fixed_step is used by method = 'dopri5_fixed' only"),
    ("reduced", reduced_with(lambda d: (d["integrator"].update(method="dopri5_fixed"),
                                        d["clearance_joints"][0].update(impact="newton"),
                                        d["clearance_joints"][0].pop("normal_law"),
                                        d["clearance_joints"][0].pop("damping_law"))),
     "integrator.fixed_step: required by method = 'dopri5_fixed' with rigid impacts (rod_slider)"),
]


STEEL_Y = {"E": 210e9, "nu": 0.3, "yield_stress": 250e6}

# elasto-plastic materials and load-unload programmes
PLASTIC = [
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "yield_stress": 0.0}}),
     "materials.bore.yield_stress: Input should be greater than 0"),
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "hardening_modulus": -1e9}}),
     "materials.bore.hardening_modulus: Input should be greater than or equal to 0"),
    ("fem", fem_with(materials={"bore": {"E": 210e9, "nu": 0.3, "hardening_modulus": 1e9}}),
     "materials.bore.hardening_modulus: needs yield_stress (Pa) in the same table"),
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "hardening": [[0.0, 250e6], [0.01, 300e6], [0.005, 320e6]]}}),
     "materials.bore.hardening: the plastic strains must increase strictly"),
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "hardening": [[0.0, 250e6], [0.01, 200e6]]}}),
     "materials.bore.hardening: the yield stresses must not decrease (no softening)"),
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "hardening": [[0.001, 250e6], [0.01, 300e6]]}}),
     "materials.bore.hardening: the first pair must be (0, yield_stress)"),
    ("fem", fem_with(materials={"bore": {**STEEL_Y, "hardening_modulus": 1e9, "hardening": [[0.0, 250e6]]}}),
     "materials.bore.hardening: give hardening_modulus or the table hardening, not both"),
    ("fem", fem_with(load={"cycles": 3}), "load: cycles > 1 needs unload = true"),
    ("fem", fem_with(load={"unload": True, "rotation_deg": 0.01}),
     "load: unload: a load programme unloads after the push, not after rotation_deg"),
]


@pytest.mark.parametrize("command, scene, message", NOT_FINITE + MISPLACED + PLASTIC,
                         ids=[m[2].split(":")[0] + str(i) for i, m in enumerate(NOT_FINITE + MISPLACED + PLASTIC)])
def test_bad_scene_value(write_scene, tmp_path, command, scene, message):
    out = tmp_path / "out"
    expect_one_line(pinbore(command, write_scene(scene), "--out", out), message, out)


@pytest.mark.parametrize("command", ["mesh", "fem", "reduced", "dynamics"])
def test_a_binary_scene_is_one_line(tmp_path, command):
    scene = tmp_path / "scene.toml"
    scene.write_bytes(b"\xff\xfe\x00\x81binary")
    extra = ["--analysis", "poincare"] if command == "dynamics" else []
    out = tmp_path / "out"
    expect_one_line(pinbore(command, scene, "--out", out, *extra), "not a text file", out)


@pytest.mark.parametrize("length, rule", [("0", "must be a finite length above 0 m"),
                                          ("nan", "must be a finite length above 0 m"),
                                          ("-0.02", "must be a finite length above 0 m"),
                                          ("inf", "must be a finite length above 0 m"),
                                          ("x", "is not a number")])
def test_calibrate_length_must_be_a_positive_length(tmp_path, length, rule):
    out = tmp_path / "out"
    done = pinbore("calibrate", tmp_path / "curve.csv", "--out", out, f"--length={length}")
    expect_one_line(done, f"--length: '{length}'" if length != "x" else "--length", out)
    assert rule in done.stderr


def test_usage_errors_are_one_line():
    done = pinbore("fem")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "required: scene, --out" in done.stderr


# meshes that could not be solved: refused before meshing, from the estimated cell count
TOO_LARGE = [
    (fem_with(mesh={"contact_size": 1e-9}), "cells expected"),
    (fem_with(geometry={"pin_radius": 8.0e-3}, load={"max_approach": 1e-9}), "cells expected"),
    (fem_with(mesh={"max_cells": 1000}), "more than the limit 1e+03"),
    (fem_with(geometry={"dim": 3, "length": 0.02}, mesh={"contact_size": 2e-5}), "cells expected"),
]


@pytest.mark.parametrize("scene, message", TOO_LARGE, ids=range(len(TOO_LARGE)))
@pytest.mark.parametrize("command", ["mesh", "fem"])
def test_a_mesh_too_large_is_refused_before_meshing(write_scene, tmp_path, scene, message, command):
    out = tmp_path / "out"
    expect_one_line(pinbore(command, write_scene(scene), "--out", out), message, out)


def modes_with(**body):
    data = tomllib.loads((ROOT / "scenes" / "modes" / "panel_aluminium_3d.toml").read_text())
    data["body"] |= body
    return data


# a flexible body's mesh likewise (Gmsh had grown to 6.9 GB over minutes, deaf to SIGTERM)
MODES_TOO_LARGE = [(modes_with(cell_size=2e-5), "cells, more than 1.5e+05"),
                   ({**modes_with(), "material": {"E": 1e-300, "nu": 0.3, "density": 2700.0}}, "material.E"),
                   ({**modes_with(), "material": {"E": 1e300, "nu": 0.3, "density": 2700.0}}, "material.E"),
                   ({**modes_with(), "material": {"E": 7e10, "nu": 0.3, "density": 1e300}}, "material.density"),
                   (modes_with(length=120.0), "cells, more than 1.5e+05"),
                   (modes_with(lug_bore_radius=1e-7), "lug_bore_radius 1e-07 m is less than cell_size / 10"),
                   (modes_with(max_cells=100), "cells, more than 100")]


@pytest.mark.parametrize("scene, message", MODES_TOO_LARGE, ids=range(len(MODES_TOO_LARGE)))
def test_a_flexible_bodys_mesh_too_large_is_refused_before_meshing(write_scene, tmp_path, scene, message):
    out = tmp_path / "out"
    expect_one_line(pinbore("modes", write_scene(scene), "--out", out), message, out)


@pytest.mark.parametrize("path", sorted((ROOT / "scenes" / "modes").glob("*.toml")), ids=lambda p: p.stem)
def test_a_flexible_bodys_cell_estimate_is_what_gmsh_meshes_within_a_factor_three(path):
    """The estimate that guards the limit against the mesh Gmsh builds: 0.85-3 times it (a
    panel's lugs refine the mesh around their bores)."""
    import gmsh

    from pinbore.core import scene as scenes
    from pinbore.fem.modes.scene import ModesScene
    from pinbore.meshes import body as body_mesh
    from pinbore.meshes.model import gmsh_session

    body = scenes.load(ModesScene, path).body
    with gmsh_session():
        body_mesh.build(gmsh, body)
        cells = sum(len(tags) for tags in gmsh.model.mesh.getElements(body.dim)[1])
    assert 0.85 <= cells / body.estimated_cells <= 3.0


@pytest.mark.parametrize("name", ["steel_c10um", "flores_c500um", "steel_lug_3d"])
def test_the_cell_estimate_matches_gmsh(name):
    """The estimate that guards the limit is within 25 % of the mesh Gmsh builds."""
    import gmsh

    from pinbore.core import scene as scenes
    from pinbore.fem.scene import FemScene
    from pinbore.meshes import pin_in_bore
    from pinbore.meshes.model import gmsh_session
    from pinbore.meshes.sizing import expected_cells

    scene = scenes.load(FemScene, ROOT / "scenes" / "fem" / f"{name}.toml")
    with gmsh_session():
        pin_in_bore.build(scene.geometry, scene.sizing, scene.load.direction_deg, scene.mesh)
        kind = 2 if scene.geometry.dim == 2 else 4   # triangles, tetrahedra
        cells = len(gmsh.model.mesh.getElementsByType(kind)[0])
    assert expected_cells(scene.geometry, scene.sizing, scene.mesh) == pytest.approx(cells, rel=0.25)


def test_report_needs_a_build_directory(tmp_path):
    (tmp_path / "a_file").write_text("x")
    for build in (tmp_path / "absent", tmp_path / "a_file"):
        done = pinbore("report", "--build", build, "--out", tmp_path / "report")
        assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
        assert "not a directory of results" in done.stderr
        assert not (tmp_path / "report").exists()


@pytest.mark.parametrize("broken, text, section", [
    ("fem/run/result.json", "{}", "FE contact"),                       # its curve.csv is missing
    ("fem/run/result.json", "[1, 2]", "FE contact"),
    ("reduced/run/summary.json", "{}", "reduced models"),
    ("reduced/run/summary.json", "garbage", "reduced models"),
    ("calibration/laws.json", '{"laws": {}}', "calibration"),
    ("dynamics/poincare/summary.json", "{}", "nonlinear dynamics"),
    ("dynamics/bifurcation/summary.json", '{"counts": 3, "wall_time_s": 1.0}', "nonlinear dynamics"),
    ("impact/run/impact.json", '{"speed_m_per_s": 1.0}', "dynamic impacts"),
    ("modes/run/modes.json", "{}", "flexible bodies"),
    ("dynamics/bifurcation/summary.json", '{"counts": {"chaotic": 2}, "wall_time_s": 1.0}',
     "nonlinear dynamics"),   # and no bifurcation.csv beside it
])
def test_report_builds_what_it_can_and_names_what_it_cannot(tmp_path, broken, text, section):
    build = tmp_path / "build"
    (build / broken).parent.mkdir(parents=True)
    (build / broken).write_text(text)
    done = pinbore("report", "--build", build, "--out", tmp_path / "report")
    assert done.returncode == 1 and "Traceback" not in done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"pinbore report: {section} section left out: ")
    page = (tmp_path / "report" / "index.html").read_text()
    assert "Not built:" in page and "<h2>" in page


# work that could not finish: refused at validation
UNBOUNDED = [
    ("reduced", reduced_with(lambda d: d.update(duration=1e4)), "output.sample_time: 5e+08 samples"),
    ("reduced", reduced_with(lambda d: d["integrator"].update(method="dopri5_fixed", fixed_step=1e-9)),
     "integrator.fixed_step: a fixed step of 1e-09 s needs 4.8e+07 steps"),
    ("reduced", reduced_with(lambda d: (d.update(duration=100.0, output={"sample_time": 1e-3}),
                                        d["integrator"].update(method="dopri5_fixed"))),
     "integrator.fixed_step: the default fixed step 1.58e-07 s"),
    ("fem", fem_with(load={"steps": 10**9}), "load.steps: Input should be less than or equal to 10000"),
]


@pytest.mark.parametrize("command, scene, message", UNBOUNDED, ids=[u[2].split(":")[0] for u in UNBOUNDED])
def test_work_that_cannot_finish_is_refused(write_scene, tmp_path, command, scene, message):
    out = tmp_path / "out"
    expect_one_line(pinbore(command, write_scene(scene), "--out", out), message, out)


def test_report_out_that_cannot_be_written_is_one_line(tmp_path):
    (tmp_path / "a_file").write_text("x")
    (tmp_path / "build").mkdir()
    done = pinbore("report", "--build", tmp_path / "build", "--out", tmp_path / "a_file" / "report")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "is a file, not a directory" in done.stderr and (tmp_path / "a_file").read_text() == "x"


# every command answers bad input in well under a second of CPU: the scene models and the
# seams validate before DOLFINx, SciPy's solvers, Gmsh or matplotlib load. Measured
# 0.3-0.8 s here (most of it Python, NumPy, pydantic and MPI starting); 1.2 s leaves room for
# a slower machine's imports while a command that loaded any of those (1.5-3 s) fails.
BAD = {
    "mesh": ("bad.toml", 'kind = "fem"\n[geometry]\nbore_radius = -1.0\n'),
    "fem": ("bad.toml", 'kind = "fem"\n[geometry]\nbore_radius = -1.0\n'),
    "impact": ("bad.toml", 'kind = "impact"\n'),
    "modes": ("bad.toml", '[body]\nshape = "bar"\n'),
    "reduced": ("bad.toml", 'kind = "planar"\nduration = 1.0\n[[bodies]]\nname = "a"\nmass = -1.0\n'),
    "dynamics": ("bad.toml", 'kind = "planar"\nduration = 1.0\n[[bodies]]\nname = "a"\nmass = -1.0\n'),
    "calibrate": ("curve.csv", "approach_m\n1\n"),
    "export": ("laws.json", "{}"),
    "study": ("study.toml", 'base = "absent.toml"\n'),
    "wear": ("bad.toml", 'kind = "wear"\nlength = -1.0\n'),
    "report": ("absent", None),
}


def test_every_command_is_held_to_it():
    from pinbore.stages import STAGE
    assert set(BAD) == set(STAGE)


@pytest.mark.parametrize("command", list(BAD))
def test_bad_input_is_answered_in_well_under_a_second_of_cpu(tmp_path, command):
    import resource
    name, text = BAD[command]
    if text is not None:
        (tmp_path / name).write_text(text)
    args = {"dynamics": ["--analysis", "poincare"], "export": ["--to", "table"]}.get(command, [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    if command == "report":
        done = pinbore("report", "--build", tmp_path / name, "--out", tmp_path / "out")
    else:
        done = pinbore(command, tmp_path / name, *args, "--out", tmp_path / "out")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert cpu < 1.2, f"{command}: {cpu:.2f} s of CPU to refuse bad input"
    assert not (tmp_path / "out").exists()


def test_a_reduced_body_that_fails_its_physical_checks_is_not_written(write_scene, tmp_path):
    """A 10 um aluminium panel meshed with cells of 20 mm: its reduced stiffness loses its
    positive definiteness in the round-off (the rigid-body motions come out stiff, a
    flexible eigenvalue negative: a NaN frequency was written as complete). One line naming
    the keys that decide it, exit 2, nothing written; the same panel 2 mm thick reduces
    (its first free-free bending mode 3.56 sqrt(E t^2 / (12 rho L^4)) = 262 Hz, within 5 %)."""
    panel = {"body": {"shape": "panel", "dim": 3, "length": 0.2, "width": 0.1, "thickness": 1e-5,
                      "cell_size": 0.02},
             "material": {"E": 7.0e10, "nu": 0.33, "density": 2700.0},
             "reduction": {"interfaces": ["edge"], "fixed_interface_modes": 4, "modes": 2}}
    out = tmp_path / "out"
    expect_one_line(pinbore("modes", write_scene(panel), "--out", out), "body.thickness", out)
    panel["body"]["thickness"] = 2e-3
    assert pinbore("modes", write_scene(panel), "--out", out).returncode == 0
    first = json.loads((out / "modes.json").read_text())["frequencies_Hz"][0]
    assert first == pytest.approx(3.5608 * math.sqrt(7e10 * 4e-6 / (12 * 2700 * 0.2 ** 4)), rel=0.05)


SMALL_PANEL = {"body": {"shape": "panel", "dim": 3, "length": 0.2, "width": 0.1, "thickness": 2e-3,
                        "cell_size": 0.02},
               "material": {"E": 7.0e10, "nu": 0.33, "density": 2700.0},
               "reduction": {"interfaces": ["edge"], "fixed_interface_modes": 4, "modes": 2}}


@pytest.fixture(scope="module")
def reduced_panel(tmp_path_factory):
    """A small panel's `pinbore modes` output (its modes.json, body.npz, mode_shapes.png)."""
    import tomli_w

    folder = tmp_path_factory.mktemp("panel")
    (folder / "panel.toml").write_text(tomli_w.dumps(SMALL_PANEL))
    assert pinbore("modes", folder / "panel.toml", "--out", folder / "modes" / "panel").returncode == 0
    return folder / "modes" / "panel"


def _edit_json(path, key, value):
    data = json.loads(path.read_text())
    data[key] = value
    path.write_text(json.dumps(data))


@pytest.mark.parametrize("corrupt", [
    lambda f: _edit_json(f / "modes.json", "frequencies_Hz", [float("nan"), 300.0]),
    lambda f: _edit_json(f / "modes.json", "mass_kg", -0.1),
    lambda f: _edit_json(f / "modes.json", "mean_axis_residual", 3.35),
    lambda f: (f / "mode_shapes.png").write_bytes((f / "mode_shapes.png").read_bytes()[:500]),
    lambda f: (f / "mode_shapes.png").write_text("not an image"),
], ids=["NaN frequency", "negative mass", "mean-axis residual", "truncated PNG", "text PNG"])
def test_the_report_marks_a_result_it_cannot_trust(tmp_path, reduced_panel, corrupt):
    """A result whose values fail its record's physical rules, or whose picture is not a
    whole PNG, is not drawn: its section is left out with one line and a note on the page,
    exit 1 (it had been shown as a result, or as a broken image, exit 0)."""
    import shutil

    build = tmp_path / "build"
    shutil.copytree(reduced_panel, build / "modes" / "panel")
    done = pinbore("report", "--build", build, "--out", tmp_path / "report")
    assert done.returncode == 0, done.stderr   # whole, it is drawn
    corrupt(build / "modes" / "panel")
    done = pinbore("report", "--build", build, "--out", tmp_path / "report")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and len(lines) == 1 and "flexible bodies section left out" in lines[0], done.stderr
    assert "Not built:" in (tmp_path / "report" / "index.html").read_text()
