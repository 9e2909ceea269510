"""make's code dependencies come from the code (core/codedeps.py writes build/deps.mk): an
edit of any module a stage imports, lazily or not, reruns that stage under make, and only
the mechanism scenes that name a laws file wait for the calibration. Checked on make itself,
in a copy of the repository where every target is up to date (`make -t`): `make -n -W FILE`
(FILE taken as just edited) must list the stage's command with FILE among the prerequisites
it found newer, for every file of the stage's import closure."""

import functools
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from conftest import ROOT

from pinbore.core import codedeps

COPIED = ["Makefile", "pyproject.toml", "requirements.lock", "CMakeLists.txt", "scenes", "studies"]
NEWER = re.compile(r"Prerequisite '([^']+)' is newer than target '([^']+)'")
COMMAND = re.compile(r"\.venv/bin/pinbore (\w+) .*--out (\S+)")


def make(tree: Path, *args: str) -> str:
    run = subprocess.run(["make", "--no-print-directory", f"PYTHON312={sys.executable}", "JOBS=1", *args],
                         cwd=tree, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return run.stdout


@pytest.fixture(scope="module")
def tree(tmp_path_factory) -> Path:
    """A copy of the repository's sources, make and scenes (no .venv, no build/: a fresh
    clone), whose targets are then all made up to date by `make -t`."""
    tree = tmp_path_factory.mktemp("clone")
    folders = {folder for folders in codedeps.repository_folders(ROOT).values() for folder in folders}
    for folder in folders:
        for path in folder.rglob("*.py"):
            if "__pycache__" not in path.parts:
                (tree / path.relative_to(ROOT)).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(path, tree / path.relative_to(ROOT))
    for name in COPIED:
        (shutil.copytree if (ROOT / name).is_dir() else shutil.copy2)(ROOT / name, tree / name)
    return tree


@pytest.fixture(scope="module")
def targets(tree) -> dict[str, list[str]]:
    """Command -> the targets whose recipe runs it, from `make -n` on the fresh copy (which
    must work: build/deps.mk is written first, with no .venv); then all made up to date."""
    dry = make(tree, "-n", "all", "impact")   # (impact: in no report)
    assert (tree / "build/deps.mk").exists()
    outs = {}
    for command, out in COMMAND.findall(dry.replace("\\\n", " ")):
        outs.setdefault(command, []).append(out)
        (tree / out).mkdir(parents=True, exist_ok=True)
    (tree / ".venv").mkdir()
    make(tree, "-t", "all", "impact")
    assert ".venv/bin/pinbore" not in make(tree, "-n", "all", "impact")
    return {command: [str(next((tree / out).iterdir()).relative_to(tree)) for out in found]
            for command, found in outs.items()}


@functools.cache
def graph() -> codedeps.Graph:
    """The repository's import graph, as make's deps.mk reads it."""
    return codedeps.Graph(codedeps.repository_folders(ROOT))


def closure_files(command: str) -> set[str]:
    """The source files of the import closure of a command's code: the command line's main
    and its stage's model and runner in the registry (pinbore/stages.py)."""
    return {path.relative_to(ROOT).as_posix() for path in graph().sources(*codedeps.commands(graph())[command])}


def test_every_stage_of_make_has_its_command():
    """The commands make runs are stages of the registry that codedeps reads, the same as
    the registry holds when imported."""
    from pinbore import stages

    assert list(codedeps.commands(graph())) == [stage.name for stage in stages.STAGES]
    makefile = (ROOT / "Makefile").read_text()
    run = set(re.findall(r"\$\(PINBORE\) (\w+)", makefile))
    assert run <= set(codedeps.commands(graph()))
    assert {"mesh", "fem", "impact", "modes", "calibrate", "reduced", "wear", "dynamics", "study",
            "report"} <= run


def test_a_stage_reruns_when_any_module_it_imports_is_edited(tree, targets):
    """For a first and a last target of every command make runs: with every file of the
    command's import closure taken as edited, make finds each of them newer than the target
    (each is a prerequisite) and lists the command; with none, nothing."""
    assert set(targets) == {"mesh", "fem", "impact", "modes", "calibrate", "reduced", "wear",
                            "dynamics", "study", "report"}
    for command, found in targets.items():
        for target in dict.fromkeys([found[0], found[-1]]):
            assert not_rerun(tree, command, target) == set(), \
                f"{target}: editing these reruns no `pinbore {command}`"
            assert ".venv/bin/pinbore" not in make(tree, "-n", target)


def not_rerun(tree: Path, command: str, target: str) -> set[str]:
    """The files of the command's import closure that, taken as edited, are no prerequisite
    make finds newer than the target; every file when make would not run the command."""
    files = closure_files(command)
    edited = [arg for path in sorted(files) for arg in ("-W", path)]
    dry = make(tree, "-n", "--debug=v", "-o", "build/deps.mk", *edited, target)
    if f".venv/bin/pinbore {command} " not in dry:
        return files
    return files - {prerequisite for prerequisite, of in NEWER.findall(dry) if of == target}


def test_a_module_dropped_from_a_stages_list_is_found(tree, targets):
    """The check above fails when build/deps.mk's list of a stage lacks a module of its
    closure (here fem/elasticity.py dropped from CODE_modes, as a hand list had dropped it)."""
    deps = tree / "build/deps.mk"
    kept = deps.read_text()
    try:
        deps.write_text("\n".join(line.replace(" fem/elasticity.py", "") if line.startswith("CODE_modes ")
                                  else line for line in kept.splitlines()) + "\n")
        assert not_rerun(tree, "modes", targets["modes"][0]) == {"fem/elasticity.py"}
    finally:
        deps.write_text(kept)


def test_editing_what_the_modal_reduction_imports_reruns_modes(tree, targets):
    """The drift the hand lists had: fem/modes/reduction.py imports fem/elasticity.py,
    meshes/model.py and laws/relief.py, which the hand list of the modes rule had missed; and
    every module that pinbore modes loads (imported in a fresh interpreter) is in its closure."""
    files = closure_files("modes")
    assert {"fem/modes/reduction.py", "fem/elasticity.py", "meshes/model.py", "laws/relief.py"} <= files
    for edited in ("fem/elasticity.py", "meshes/model.py", "laws/relief.py"):
        assert ".venv/bin/pinbore modes " in make(tree, "-n", "-o", "build/deps.mk", "-W", edited,
                                                 targets["modes"][0])
    # what the stage's model and runner load (the command line and the registry with them)
    from pinbore import stages

    modes = stages.STAGE["modes"]
    loaded = subprocess.run(
        [sys.executable, "-c", "import sys; import pinbore.cli; from pinbore.stages import STAGE, resolve; "
         f"resolve({modes.model!r}); resolve({modes.run!r}); "
         "print(' '.join(m for m in sys.modules if m.startswith('pinbore')))"],
        capture_output=True, text=True, check=True).stdout.split()
    closure = graph().closure(*codedeps.commands(graph())["modes"])
    assert {codedeps.project_module(m, graph().files) for m in loaded} - {None} - closure == set()


def test_an_edit_outside_a_stage_reruns_nothing_of_it(tree, targets):
    """The closure is the stage's, not the package's: an edit of the multibody engine's
    Python reruns no FE run or mesh."""
    assert "reduced/mechanism/model.py" not in closure_files("fem") | closure_files("mesh")
    for command in ("fem", "mesh"):
        dry = make(tree, "-n", "-o", "build/deps.mk", "-W", "reduced/mechanism/model.py",
                   targets[command][0])
        assert ".venv/bin/pinbore" not in dry


def test_only_the_scenes_that_name_a_laws_file_wait_for_the_calibration(tree, targets):
    """A mechanism run waits for build/calibration/laws.json exactly when its scene's TOML
    names a laws_file (parsed, not grepped)."""
    dry = make(tree, "-n", "--debug=v", "-o", "build/deps.mk", "-W", "build/calibration/laws.json", "reduced")
    waiting = {Path(of).parent.name for prerequisite, of in NEWER.findall(dry)
               if prerequisite == "build/calibration/laws.json" and of.startswith("build/reduced/")}
    reading = {path.stem for path in (ROOT / "scenes/reduced").glob("*.toml")
               if "laws_file" in tomllib.loads(path.read_text())}
    assert reading and waiting == reading


def test_the_closure_follows_lazy_imports_registries_and_packages(tmp_path):
    """On a small package: an import inside a function counts; a module a registry names in a
    string counts when the registry loads by name; a package above a module counts for what
    importing it runs, not for its functions' imports; a dispatcher's entry is its function."""
    (tmp_path / "pyproject.toml").write_text(
        '[tool.scikit-build]\nwheel.packages = { "pinbore" = "pinbore", "pinbore/core" = "core" }\n')
    files = {
        "pinbore/__init__.py": "def __getattr__(name):\n    from pinbore import api\n",
        "pinbore/api.py": "",
        "pinbore/cli.py": "import sys\ndef _a():\n    from pinbore.core import a\ndef _b():\n    from pinbore.core import b\n",
        "core/__init__.py": "from . import base\n",
        "core/base.py": "",
        "core/a.py": "def f():\n    from .lazy import g\n",
        "core/lazy.py": "import importlib\nTABLE = {'x': 'pinbore.core.named'}\n"
                        "def load(k):\n    return importlib.import_module(TABLE[k])\n",
        "core/named.py": "",
        "core/b.py": "NOT_LOADED = 'pinbore.core.named'\n",
    }
    for name, text in files.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    graph = codedeps.Graph(codedeps.repository_folders(tmp_path))
    assert graph.closure("pinbore.cli:_a") == {"pinbore", "pinbore.cli", "pinbore.core", "pinbore.core.base",
                                               "pinbore.core.a", "pinbore.core.lazy", "pinbore.core.named"}
    assert graph.closure("pinbore.cli:_b") == {"pinbore", "pinbore.cli", "pinbore.core", "pinbore.core.base",
                                               "pinbore.core.b"}
    assert "pinbore.api" in graph.closure("pinbore")   # the package read whole: its lazy attribute
