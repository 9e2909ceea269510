"""The documentation cannot drift from the code: the committed JSON Schemas of the scenes are
what the scene models give now, every shipped scene is valid under the model of its schema,
every number of a scene has a unit, the README stays short and points at pages that exist, and
the documentation builds without a warning (`make docs`: broken links and references, missing
images and unresolved names count).

Only the scene models are imported (pydantic; meshes.model and the impact scene reach the
compiled core's laws), not DOLFINx; the build is a subprocess."""

import json
import re
import subprocess
import sys
import tomllib

import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT / "docs" / "_ext"))
import scene_reference  # noqa: E402  (docs/_ext: the scene reference and the schemas)

SCENES = {scene.name: scene for scene in scene_reference.SCENES}
README_LINES = 300


@pytest.mark.parametrize("name", sorted(SCENES))
def test_committed_schema_is_the_models(name):
    path = scene_reference.SCHEMAS / f"{name}.schema.json"
    assert path.exists(), f"{path.relative_to(ROOT)} missing: run make docs"
    committed = json.loads(path.read_text(encoding="utf-8"))
    assert committed == scene_reference.schema(SCENES[name]), (
        f"{path.relative_to(ROOT)} differs from the scene model: run make docs and commit it")


def shipped() -> list:
    return [(name, path) for name, scene in sorted(SCENES.items())
            for path in sorted((ROOT / "scenes" / scene.folder).glob("*.toml"))]


@pytest.mark.parametrize("name, path", shipped(), ids=lambda v: getattr(v, "name", v))
def test_shipped_scene_is_valid_under_its_schema_model(name, path):
    from pinbore.core import scene as scenes

    data = tomllib.loads(path.read_text(encoding="utf-8"))
    model = scene_reference.scene_model(SCENES[name], data)
    scenes.validate(model, data, str(path))    # one InputError line if not


def test_every_scene_folder_and_mechanism_kind_is_documented():
    folders = {p.name for p in (ROOT / "scenes").iterdir() if p.is_dir()}
    assert folders == {scene.folder for scene in SCENES.values()}
    from pinbore.reduced.mechanism.kinds import KINDS

    documented = set(scene_reference.models(SCENES["mechanism"]))
    assert {kind.scene for kind in KINDS.values()} == documented


def test_every_number_has_a_unit_and_every_listed_unit_a_key():
    missing, stale = scene_reference.check_units()
    assert not missing, f"numbers without a unit (state it in the description or units.toml): {missing}"
    assert not stale, f"docs/_ext/units.toml names keys no model has: {stale}"


def test_readme_is_short_and_points_at_pages_that_exist():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= README_LINES
    links = re.findall(r"\]\(([^)#]+)\)", text)
    assert links
    missing = [link for link in links if not link.startswith("http") and not (ROOT / link).exists()]
    assert not missing, missing


def test_readme_test_command_is_what_ci_runs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "make test   # the test suite (what CI runs: .ci/run)" in readme
    assert "\nmake test\n" in (ROOT / ".ci" / "run").read_text() + "\n"


def test_docs_build_without_warnings(tmp_path):
    """The whole site, offline, as `make docs` builds it (about 30 s: autodoc imports every
    module)."""
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-q",
                           "-b", "html", "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"),
                           str(tmp_path / "html")], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-4000:]
    assert (tmp_path / "html" / "scenes" / "fem.html").exists()


def test_the_docs_extra_admits_the_locked_versions():
    """pyproject's `docs` extra states ranges, requirements.lock the exact versions `make`
    installs: each locked documentation package lies in its range."""
    from packaging.requirements import Requirement

    extra = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]["docs"]
    locked = dict(line.lower().split("==") for line in (ROOT / "requirements.lock").read_text().split())
    for text in extra:
        req = Requirement(text)
        version = locked.get(req.name.lower())
        assert version is not None, f"{req.name} is not in requirements.lock"
        assert req.specifier.contains(version), f"{req.name}=={version} is outside {req.specifier}"


def bench_tables() -> list[tuple[str, dict]]:
    """(CSV path, options) of each `bench-table` of docs/benchmarks.md."""
    text = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```\{bench-table\} (\S+)\n((?::[\w-]+:.*\n)*)```", text)
    return [(path, dict(re.findall(r"^:([\w-]+): (.*)$", options, re.MULTILINE)))
            for path, options in blocks]


def test_every_benchmark_table_is_on_the_benchmarks_page():
    """Each bench/*.csv is shown by a bench-table, and each bench-table names columns its CSV
    has (docs/_ext/bench_table.py; the build fails on a missing one, this says which at once)."""
    import csv

    import bench_table

    tables = bench_tables()
    shown = {(ROOT / "docs" / path).resolve() for path, _ in tables}
    assert set((ROOT / "bench").glob("*.csv")) <= shown, "bench/*.csv not on docs/benchmarks.md"
    for path, options in tables:
        with open(ROOT / "docs" / path, newline="", encoding="utf-8") as f:
            header = next(csv.reader(f))
        named = [name for name, _, _ in bench_table.column_specs(options["columns"])]
        named += [name for name, _, _ in bench_table.conditions(options.get("where", ""))]
        assert set(named) <= set(header), f"{path}: no column {set(named) - set(header)}"
