"""pinbore from Python: each stage run in process on a scene file or a dict, its result read
back as a typed object (the model of the file the stage wrote, that the next stage reads).

    import pinbore
    curve = pinbore.run("fem", "scenes/fem/steel_c100um.toml", out="build/api/fem")   # Curve
    laws = pinbore.calibrate(["build/api/fem/curve.csv"], out="build/api/cal")        # LawsFile
    summary = pinbore.run("reduced", {"kind": "planar", ...}, out="build/api/run")    # Summary
    pinbore.laws.load("build/api/cal/laws.json")["liu"](2e-6)                         # N

A stage is the registry's (pinbore.stages), what `pinbore <command>` runs: the same checks,
the same atomic output folder. Bad input raises pinbore.core.errors.InputError with the command's
one line; a run that stops early (non-convergence, a blow-up) still returns what it kept,
marked in its status (`result.status`, `summary.status`). A scene given as a dict is written
as TOML beside nothing of the user's: to a temporary file, its `*_file` keys made absolute
against `base` (default: the working folder), as a scene file's are against its folder
(core.scene.scene_file, as the study writes its points).
"""

import contextlib
import os
from pathlib import Path
from types import SimpleNamespace

from pinbore import stages
from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.output import declared_inputs, reserved


def _path(name: str, value) -> Path:
    """An argument that names a file or folder, as a Path; InputError naming the argument."""
    if not isinstance(value, (str, os.PathLike)) or not str(value).strip():
        raise InputError(f"{name}: {value!r} must be a path (a str or pathlib.Path)")
    return Path(value)


@contextlib.contextmanager
def _scene_file(scene, base):
    """The scene's file for the block: its own, or a dict's written as a temporary scene
    file (core.scene.scene_file: its relative names taken from `base`, default the working
    folder; an error of the block names the dict, `scene`, not that file)."""
    if not isinstance(scene, dict):
        yield _path("scene", scene)
        return
    with scenes.scene_file(scene, _path("base", base or ".").absolute()) as path:
        yield path


def scene(source, base=None):
    """The validated scene model of a file or a dict, by its `kind` (pinbore.stages: fem,
    impact, planar, spatial, wear; a modes scene has none, but a [body] table)."""
    with _scene_file(source, base) as path:
        stage, data = stages.of_scene(scenes.read_toml(path), str(path))
        return stage.validate(data, str(path))


def run(stage: str, source, out, base=None):
    """Run a scene (a file or a dict) through `stage` (a stage of pinbore.stages with a typed
    result: fem, impact, modes, reduced, wear) as `pinbore <stage> SCENE --out OUT` would, in
    process (the scene and the files it names declared as inputs, which `out` may not hold);
    its result, read back typed (the model of the file the stage wrote)."""
    known = stages.with_result()
    if stage not in known:
        raise ValueError(f"stage: {stage!r} is unknown; valid: {', '.join(known)}")
    out = _path("out", out)
    with _scene_file(source, base) as path, \
            declared_inputs(known[stage].inputs(SimpleNamespace(scene=path))), \
            reserved(out):   # out checked and locked before the work, as the CLI holds it
        known[stage].run_scene(path, out)
    return known[stage].read_result(out)


def calibrate(curves, out, length=None, per_length=None, impacts=()):
    """Fit and rank the laws on FE curves (curve.csv paths), the restitution on FE impacts
    (impact.json paths): the laws file (pinbore.laws.lawsfile.LawsFile)."""
    from pinbore.calibration import run   # noqa: PLC0415
    from pinbore.laws import lawsfile   # noqa: PLC0415

    if isinstance(curves, (str, os.PathLike)) or isinstance(impacts, (str, os.PathLike)):
        raise InputError("curves, impacts: lists of paths (a single path: [path])")
    curves = [str(_path(f"curves.{k}", c)) for k, c in enumerate(curves)]
    impacts = [str(_path(f"impacts.{k}", i)) for k, i in enumerate(impacts)]
    out = _path("out", out)
    with declared_inputs([*curves, *impacts]), reserved(out):
        run.run(curves, out, length, per_length, impacts)
    return lawsfile.read(out / "laws.json")
