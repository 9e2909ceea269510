"""The floors of the package: data flows one way, core -> laws -> meshes -> fem ->
calibration -> reduced -> the roof (CLI and report), and no module imports itself round a
circle. Checked on the source (every `import` statement, at module level or inside a
function), so a late import cannot hide a circle."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT, main_in_child

from pinbore.core import codedeps

# folder -> (package, floor); the roof is pinbore/ itself
FLOORS = {"core": ("pinbore.core", 0), "laws": ("pinbore.laws", 1), "meshes": ("pinbore.meshes", 2),
          "fem": ("pinbore.fem", 3), "calibration": ("pinbore.calibration", 4),
          "reduced": ("pinbore.reduced", 5), "pinbore": ("pinbore", 6)}


def modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the package (rooms, the subfolders of a floor,
    included), as pinbore.core.codedeps reads them for make and the caches."""
    return {name: path for name, path in codedeps.modules(codedeps.repository_folders(ROOT)).items()
            if path is not None}


def floor(name: str) -> int:
    for package, level in FLOORS.values():
        if package != "pinbore" and (name == package or name.startswith(package + ".")):
            return level
    return FLOORS["pinbore"][1]


def imports(path: Path, name: str, known: set[str]) -> set[str]:
    """The package's modules that `path` imports, at module level or in a function
    (`from pinbore.x import y` counts y when y is a module, else pinbore.x): those of
    codedeps, which make's dependencies follow, without the modules a registry names in
    strings (it loads them by name, not by import)."""
    return codedeps.imported(ast.walk(ast.parse(path.read_text(), str(path))), name,
                             path.stem == "__init__", known, strings=False)


def graph() -> dict[str, set[str]]:
    found = modules()
    return {name: imports(path, name, set(found)) for name, path in found.items()}


def test_every_import_goes_down_or_across():
    wrong = [f"{a} (floor {floor(a)}) imports {b} (floor {floor(b)})"
             for a, targets in graph().items() for b in sorted(targets) if floor(b) > floor(a)]
    assert not wrong, "\n".join(wrong)


def test_no_import_circle():
    edges = graph()
    state, circles = {}, []

    def visit(node, trail):
        state[node] = "open"
        for nxt in sorted(edges[node]):
            if state.get(nxt) == "open":
                circles.append(" -> ".join(trail[trail.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, trail + [nxt])
        state[node] = "done"

    for start in sorted(edges):
        if start not in state:
            visit(start, [start])
    assert not circles, "\n".join(circles)


def test_nothing_below_the_roof_sees_argparse():
    users = [name for name, path in modules().items() if floor(name) < FLOORS["pinbore"][1]
             and "argparse" in {alias.name for node in ast.walk(ast.parse(path.read_text()))
                                if isinstance(node, ast.Import) for alias in node.names}]
    assert not users


@pytest.mark.parametrize("folder", [f for f in FLOORS if f != "pinbore"])
def test_a_floor_folder_is_no_top_level_package(folder):
    """Only `pinbore` is importable; `import fem` (e.g. from the repository's root, where the
    folder is on the path) fails instead of loading a second copy under another name."""
    run = subprocess.run([sys.executable, "-c", f"import {folder}"], cwd=ROOT,
                         capture_output=True, text=True)
    assert run.returncode != 0 and "ImportError" in run.stderr
    assert subprocess.run([sys.executable, "-c", f"import pinbore.{folder}"], cwd=ROOT).returncode == 0


def test_meshing_loads_no_dolfinx(tmp_path):
    """`pinbore mesh` needs Gmsh and the scene model, not the FE solver."""
    code = ("import sys; from pinbore.cli import main; "
            f"assert main(['mesh', {str(ROOT / 'scenes/fem/steel_c100um.toml')!r}, '--out', "
            f"{str(tmp_path / 'mesh')!r}]) == 0; "
            "assert not any(m.split('.')[0] in ('dolfinx', 'petsc4py') for m in sys.modules), "
            "'dolfinx loaded'")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "mesh" / "mesh.msh").exists()


# ---- the rooms of a floor: reduced/ holds the mechanism model, the nonlinear dynamics and the
# report section; fem/ the quasi-static solver and the dynamic impact
MECHANISM = "pinbore.reduced.mechanism"
BACK_ENDS = {f"{MECHANISM}.planar", f"{MECHANISM}.spatial"}


def test_kinematic_back_ends_never_import_each_other():
    edges = graph()
    wrong = [f"{a} imports {b}" for a in BACK_ENDS for b in edges[a] if b in BACK_ENDS]
    assert not wrong, "\n".join(wrong)


def test_only_the_registry_names_a_back_end():
    """The engine, the bodies' interface and every user of the mechanism reach a body kind
    through the registry (reduced.mechanism.kinds: Kind.bodies()), never by importing it, so
    a third kind plugs in there without touching the joints."""
    wrong = [f"{a} imports {b}" for a, targets in graph().items() if a not in BACK_ENDS
             for b in targets if b in BACK_ENDS]
    assert not wrong, "\n".join(wrong)


def test_rooms_go_one_way():
    """The mechanism model is below the nonlinear dynamics and the report section; the
    quasi-static FE solver does not reach into the dynamic impact's room."""
    below = {"pinbore.reduced.mechanism": ("pinbore.reduced.dynamics", "pinbore.reduced.report"),
             "pinbore.reduced.dynamics": ("pinbore.reduced.report",)}
    edges = graph()
    wrong = [f"{a} imports {b}" for a, targets in edges.items() for room, above in below.items()
             if a.startswith(room) for b in targets if b.startswith(above)]
    fem_core = [a for a in edges if a.startswith("pinbore.fem.") and not a.startswith("pinbore.fem.impact")]
    wrong += [f"{a} imports {b}" for a in fem_core for b in edges[a] if b.startswith("pinbore.fem.impact")]
    assert not wrong, "\n".join(wrong)


SCENE_SIDE = [f"{MECHANISM}.{name}" for name in ("scene", "kinds", "summary", "verdict", "layout")]


def test_scene_side_of_the_mechanism_builds_no_model():
    """Validating a mechanism scene (and reading its summary) loads neither the model's build,
    the compiled core nor DOLFINx: a scene with a bad number is one line in well under a second
    of CPU."""
    code = ("import sys; " + "; ".join(f"import {m}" for m in SCENE_SIDE)
            + f"; assert not {{'{MECHANISM}.model', 'pinbore.core.cpp', 'dolfinx'}} & set(sys.modules), 'loaded'")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr


@pytest.mark.parametrize("command", ["reduced", "dynamics"])
def test_a_bad_mechanism_scene_costs_well_under_a_second(tmp_path, command):
    """A scene with a negative mass: exit 2, one line naming the key, before the model or
    DOLFINx load (the child's CPU time, import of the CLI included)."""
    scene = (ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(scene.replace("mass = 0.30", "mass = -0.30"))
    extra = ["--analysis", "poincare"] if command == "dynamics" else []
    run = main_in_child(command, bad, "--out", tmp_path / "out", *extra)
    assert run.returncode == 2, run.stderr
    assert "bodies" in run.stderr and "mass" in run.stderr and len(run.stderr.strip().splitlines()) == 1
    assert float(run.stdout) < 1.0
    assert not (tmp_path / "out").exists()


# where a branch on the kind of mechanism would hide: the users of the mechanism model
KIND_NEUTRAL = ["reduced/mechanism/model.py", "reduced/mechanism/run.py",
                "reduced/mechanism/outputs.py", "reduced/mechanism/kernel.py",
                "reduced/dynamics/flow.py", "reduced/dynamics/studies.py",
                "reduced/dynamics/parameters.py", "reduced/report.py",
                "bench/multibody.py", "bench/sweep.py", "bench/stress.py"]


@pytest.mark.parametrize("name", KIND_NEUTRAL)
def test_no_branch_on_the_kind_of_mechanism(name):
    """Every command, the report and the benchmarks take any mechanism through the registry
    (reduced.mechanism.kinds): no comparison with a kind's name and no test of a kind's scene
    class outside it."""
    tree = ast.parse((ROOT / name).read_text())
    wrong = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            about_kind = any(isinstance(side, ast.Attribute) and side.attr in ("kind", "model")
                             or isinstance(side, ast.Subscript) and isinstance(side.slice, ast.Constant)
                             and side.slice.value in ("kind", "model") for side in sides)
            for side in sides:
                if isinstance(side, ast.Constant) and (side.value in ("planar", "spatial") or about_kind
                                                       and side.value == "reduced"):
                    wrong.append(f"line {node.lineno}: compares with {side.value!r}")
        if isinstance(node, ast.Name) and node.id in ("PlanarScene", "SpatialScene"):
            wrong.append(f"line {node.lineno}: names {node.id}")
    assert not wrong, "\n".join(wrong)


def test_the_scene_knows_every_damping_law():
    """The scene lists the hysteresis laws by name (validating it loads no law module); they
    are exactly those of pinbore.laws.dissipative."""
    from pinbore.laws.dissipative import HYSTERESIS
    from pinbore.reduced.mechanism.joints.contact import HYSTERESIS_LAWS

    assert sorted(HYSTERESIS_LAWS) == sorted(HYSTERESIS)


def test_every_package_folder_is_installed():
    """pyproject.toml maps each floor's package to its folder (scikit-build-core copies a
    folder whole, its rooms included, into a wheel: `pip install .`), every floor and nothing
    else, so that a new floor cannot work in the editable install and be missing from a
    wheel; the compiled core installs into the core's package."""
    import tomllib

    mapped = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["scikit-build"]["wheel"]["packages"]
    assert mapped == {package.replace(".", "/"): folder for folder, (package, _) in FLOORS.items()}
    assert "DESTINATION pinbore/core" in (ROOT / "CMakeLists.txt").read_text()


def test_no_root_folder_imports_as_part_of_the_package():
    """bench/, tests/ and docs/ are not pinbore's: none imports as pinbore.<folder> (the
    editable install lists the repository's root among the package's folders; pinbore
    keeps only its own)."""
    import importlib

    for folder in ("bench", "tests", "docs"):
        with pytest.raises(ImportError):
            importlib.import_module(f"pinbore.{folder}")


# the ideal joints' own models and primitives, whose types share names with clearance joints'
# (a spatial ideal joint may be revolute, cylindrical or spherical): (file, top-level name)
IDEAL_JOINTS = {("reduced/mechanism/scene.py", "Joint"), ("reduced/mechanism/spatial.py", "joint_primitives")}


def named_types(node, names) -> list[str]:
    """The names among `names` that a comparison's sides hold as constants (alone or in a
    tuple, list or set)."""
    found = []
    for side in [node.left, *node.comparators]:
        items = side.elts if isinstance(side, (ast.Tuple, ast.List, ast.Set)) else [side]
        found += [item.value for item in items if isinstance(item, ast.Constant) and item.value in names]
    return found


def test_no_branch_on_a_clearance_joint_type():
    """A clearance joint's type is named in its own module (reduced.mechanism.joints) and the
    registry that maps it there: no comparison with a type's name anywhere else in the
    package or the benchmarks (the ideal joints' own model and primitives aside), so a new
    type is one module and one registry line."""
    from pinbore.reduced.mechanism.joints import TYPES

    files = [path for path in modules().values() if ROOT / "reduced/mechanism/joints" not in path.parents]
    wrong = []
    for path in files + sorted((ROOT / "bench").glob("*.py")):
        name = str(path.relative_to(ROOT))
        for top in ast.parse(path.read_text()).body:
            if (name, getattr(top, "name", None)) in IDEAL_JOINTS:
                continue
            wrong += [f"{name} line {node.lineno}: compares with {', '.join(map(repr, types))}"
                      for node in ast.walk(top) if isinstance(node, ast.Compare)
                      for types in [named_types(node, TYPES)] if types]
    assert not wrong, "\n".join(wrong)


# the registries that name stages and scene kinds: the stages' (pinbore.stages) and the
# mechanism's kinds' (reduced.mechanism.kinds)
REGISTRIES = {"pinbore/stages.py", "reduced/mechanism/kinds.py"}
# a rule of a model, not a dispatch: the wear of a joint takes a planar mechanism
KIND_RULES = {("reduced/wear/run.py", "planar")}


def stage_and_kind_names() -> set[str]:
    from pinbore import stages

    return {s.name for s in stages.STAGES} | {kind for s in stages.STAGES for kind in s.kinds}


def test_only_the_registry_branches_on_a_stage_or_a_kind():
    """The command line, the API, the study, the report and make's dependencies read one
    registry (pinbore.stages): no module of the package compares with a stage's or a scene
    kind's name, nor holds a table keyed by them (a scene model names its own kind as a
    Literal, no comparison)."""
    names = stage_and_kind_names()
    wrong = []
    for path in modules().values():
        name = path.relative_to(ROOT).as_posix()
        if name in REGISTRIES:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare):
                wrong += [f"{name} line {node.lineno}: compares with {value!r}"
                          for value in named_types(node, names) if (name, value) not in KIND_RULES]
            elif isinstance(node, ast.Dict):
                keys = [k.value for k in node.keys if isinstance(k, ast.Constant) and k.value in names]
                if len(keys) > 1:
                    wrong.append(f"{name} line {node.lineno}: a table keyed by {', '.join(keys)}")
            elif isinstance(node, ast.Match):
                wrong.append(f"{name} line {node.lineno}: a match statement")
    assert not wrong, "\n".join(wrong)


def test_the_registry_names_what_exists():
    """Every string entry of a stage ("module:name") names a loadable object, its model a
    pydantic model or a validating function; its help names the files it writes, its typed
    result among them; the mechanism's kinds are those of reduced.mechanism.kinds; the
    commands make reads (core.codedeps, by `ast`) are the stages."""
    import pydantic

    from pinbore import stages
    from pinbore.reduced.mechanism import kinds

    for stage in stages.STAGES:
        entries = [stage.run, *filter(None, (stage.model, stage.arguments, stage.point)),
                   *(s.function for s in stage.sections), *stage.answers,
                   *([stage.result[1]] if stage.result else [])]
        for entry in entries:
            assert callable(stages.resolve(entry)), f"{stage.name}: {entry}"
        if stage.model:
            model = stages.resolve(stage.model)
            assert not isinstance(model, type) or issubclass(model, pydantic.BaseModel)
        assert bool(stage.point) == bool(stage.kinds) == bool(stage.result), stage.name
        assert all(f"/{file}" in stage.description for file in stage.outputs), stage.name
        assert stage.result is None or stage.result[0] in stage.outputs
    assert stages.STAGE["reduced"].kinds == tuple(kinds.KINDS)
    graph = codedeps.Graph(codedeps.repository_folders(ROOT))
    assert list(codedeps.commands(graph)) == list(stages.STAGE)


def test_a_scene_is_validated_without_its_stage_loading(tmp_path):
    """Validating a scene of each kind (pinbore.scene) loads its model alone: neither DOLFINx,
    Gmsh nor matplotlib."""
    scenes = [ROOT / "scenes/fem/steel_c100um.toml", ROOT / "scenes/modes/link_steel_2d.toml",
              *sorted((ROOT / "scenes/impact").glob("*.toml"))[:1],
              ROOT / "scenes/reduced/slider_crank_flores2004.toml", *sorted((ROOT / "scenes/wear").glob("*.toml"))[:1]]
    code = ("import sys, pinbore; " + "; ".join(f"pinbore.scene({str(s)!r})" for s in scenes)
            + "; loaded = {m.split('.')[0] for m in sys.modules} & {'dolfinx', 'gmsh', 'matplotlib'}"
            + "; assert not loaded, loaded")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
