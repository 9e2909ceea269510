"""The floors of the package: data flows one way, core -> laws -> meshes -> fem ->
calibration -> reduced -> the roof (CLI and report), and no module imports itself round a
circle. Checked on the source (every `import` statement, at module level or inside a
function), so a late import cannot hide a circle."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT

# folder -> (package, floor); the roof is pinbore/ itself
FLOORS = {"core": ("pinbore.core", 0), "laws": ("pinbore.laws", 1), "meshes": ("pinbore.meshes", 2),
          "fem": ("pinbore.fem", 3), "calibration": ("pinbore.calibration", 4),
          "reduced": ("pinbore.reduced", 5), "pinbore": ("pinbore", 6)}


def modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the package."""
    found = {}
    for folder, (package, _) in FLOORS.items():
        for path in sorted((ROOT / folder).glob("*.py")):
            found[package if path.stem == "__init__" else f"{package}.{path.stem}"] = path
    return found


def floor(name: str) -> int:
    for package, level in FLOORS.values():
        if package != "pinbore" and (name == package or name.startswith(package + ".")):
            return level
    return FLOORS["pinbore"][1]


def imports(path: Path, name: str, known: set[str]) -> set[str]:
    """The package's modules that `path` imports (`from pinbore.x import y` counts y when y is
    a module, else pinbore.x)."""
    out = set()
    package = name if path.stem == "__init__" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1]
                                + ([base] if base else []))
            targets = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base
                       for alias in node.names]
        else:
            continue
        out |= {t for t in targets if t in known and t != name}
    return out


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
