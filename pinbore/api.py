"""pinbore from Python: each stage run in process on a scene file or a dict, its result read
back as a typed object (the model of the file the stage wrote, that the next stage reads).

    import pinbore
    curve = pinbore.run("fem", "scenes/fem/steel_c100um.toml", out="build/api/fem")   # Curve
    laws = pinbore.calibrate(["build/api/fem/curve.csv"], out="build/api/cal")        # LawsFile
    summary = pinbore.run("reduced", {"kind": "planar", ...}, out="build/api/run")    # Summary
    pinbore.laws.load("build/api/cal/laws.json")["liu"](2e-6)                         # N

A stage is the command's own function (what `pinbore <command>` runs): the same checks, the
same atomic output folder. Bad input raises pinbore.core.errors.InputError with the command's
one line; a run that stops early (non-convergence, a blow-up) still returns what it kept,
marked in its status (`result.status`, `summary.status`). A scene given as a dict is written
as TOML beside nothing of the user's: to a temporary file, its `*_file` keys made absolute
against `base` (default: the working folder), as a scene file's are against its folder.
"""

import contextlib
import os
import tempfile
from pathlib import Path

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.output import declared_inputs, reserved


def _path(name: str, value) -> Path:
    """An argument that names a file or folder, as a Path; InputError naming the argument."""
    if not isinstance(value, (str, os.PathLike)) or not str(value).strip():
        raise InputError(f"{name}: {value!r} must be a path (a str or pathlib.Path)")
    return Path(value)


def _toml_ready(node, where: str = "") -> None:
    """A dict scene TOML can hold: string keys, no None (TOML has no null: leave the key out);
    InputError naming the key."""
    if isinstance(node, dict):
        for key, value in node.items():
            if not isinstance(key, str):
                raise InputError(f"scene: {where + ': ' if where else ''}the key {key!r} must be a string")
            _toml_ready(value, f"{where}.{key}" if where else key)
    elif isinstance(node, (list, tuple)):
        for k, value in enumerate(node):
            _toml_ready(value, f"{where}.{k}")
    elif node is None:
        raise InputError(f"scene: {where}: None is no TOML value (leave the key out for its default)")


@contextlib.contextmanager
def _scene_file(scene, base):
    """The scene's file for the block: its own, or a dict's written to a temporary folder
    (removed after the block; an error of the block names the dict, `scene`, not that file)."""
    if not isinstance(scene, dict):
        yield _path("scene", scene)
        return
    import tomli_w   # noqa: PLC0415

    _toml_ready(scene)
    with tempfile.TemporaryDirectory(prefix="pinbore-scene-") as folder:
        path = Path(folder) / "scene.toml"
        path.write_text(tomli_w.dumps(scenes.absolute_files(scene, _path("base", base or ".").resolve())))
        try:
            yield path
        except InputError as err:
            raise InputError(str(err).replace(str(path), "scene")) from None


def scene(source, base=None):
    """The validated scene model of a file or a dict, by its `kind` (fem, impact, planar,
    spatial; a modes scene has none, but a [body] table)."""
    with _scene_file(source, base) as path:
        data = scenes.read_toml(path)
        kind = data.get("kind", "modes" if "body" in data else None)
        from pinbore.reduced.mechanism import kinds   # noqa: PLC0415 (pydantic only)

        if isinstance(kind, str) and (kind in kinds.KINDS or kind in kinds.RENAMED_KINDS):
            return kinds.load(path)
        if kind == "fem":
            from pinbore.fem.scene import FemScene as model   # noqa: PLC0415
        elif kind == "impact":
            from pinbore.fem.impact.scene import ImpactScene as model   # noqa: PLC0415
        elif kind == "modes":
            from pinbore.fem.modes.scene import ModesScene as model   # noqa: PLC0415
        else:
            raise InputError(f"{'scene' if isinstance(source, dict) else source}: kind: {kind!r} is "
                             "unknown; valid: fem, impact, planar, spatial (a modes scene: a "
                             "[body] table)")
        return scenes.load(model, path)


def _fem(out):
    from pinbore.fem import curve, run   # noqa: PLC0415

    return run.run, lambda: curve.read(out / "curve.csv")


def _impact(out):
    from pinbore.fem.impact import file, run   # noqa: PLC0415

    return run.run, lambda: file.read_summary(out / "impact.json")


def _modes(out):
    from pinbore.fem.modes import file, run   # noqa: PLC0415

    return run.run, lambda: file.read(out / "body.npz")


def _reduced(out):
    from pinbore.reduced.mechanism import run, summary   # noqa: PLC0415

    return run.run, lambda: summary.read(out / "summary.json")


# stage -> (its run function, the reader of its result), and what the result is
STAGES = {"fem": _fem,           # the load-approach curve, pinbore.fem.curve.Curve
          "impact": _impact,     # the impact's summary, pinbore.fem.impact.file.ImpactSummary
          "modes": _modes,       # the reduced body, pinbore.fem.modes.file.ReducedBody
          "reduced": _reduced}   # the mechanism's summary, pinbore.reduced.mechanism.summary.Summary


def run(stage: str, source, out, base=None):
    """Run a scene (a file or a dict) through `stage` (fem, impact, modes, reduced) as
    `pinbore <stage> SCENE --out OUT` would, in process (the scene and the files it names
    declared as inputs, which `out` may not hold); its result, read back typed."""
    if stage not in STAGES:
        raise ValueError(f"stage: {stage!r} is unknown; valid: {', '.join(STAGES)}")
    out = _path("out", out)
    runner, result = STAGES[stage](out)
    with _scene_file(source, base) as path, declared_inputs([path, *scenes.referenced_files(path)]), \
            reserved(out):   # out checked and locked before the work, as the CLI holds it
        runner(path, out)
    return result()


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
