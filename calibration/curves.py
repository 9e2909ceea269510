"""FE load-approach curves as the calibration reads them, checked before any fit."""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.core.scene import RUN_AGAIN, load_json, validate
from pinbore.fem import curve as fe_curve
from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import Joint

STAGE = "push"   # the calibration reads the radial push


@dataclass(frozen=True)
class Curve:
    """One FE curve: approach (m), force per length (N/m), half-angle (deg) and its joint."""

    name: str
    approach: np.ndarray
    force: np.ndarray
    half_angle: np.ndarray | None
    joint: Joint
    housing_ratio: float
    similar_materials: bool


def read_curve(path, length: float | None, min_points: int = 3) -> Curve:
    """Read the radial push of DIR/curve.csv (a 2D curve: forces per unit length, N/m) and
    the scene in DIR/result.json. `length` (m) is the axial length given to laws that need
    one; None takes the bore diameter."""
    path = Path(path)
    fe = fe_curve.read(path)
    approach, force = (fe_curve.column(2, key).name for key in ("approach", "force"))
    if fe.dim != 2:
        raise InputError(f"{path}: {fe_curve.column(fe.dim, 'force').name}: units do not match; "
                         f"calibration reads 2D curves with {force} "
                         f"({fe_curve.column(2, 'force').unit})")
    push = fe.only(STAGE)
    if push.points < min_points:
        raise InputError(f"{path}: {push.points} points; a fit of 2 parameters needs at least "
                         f"{min_points}")
    if np.any(push.approach <= 0) or np.any(np.diff(push.approach) <= 0):
        row = int(np.argmax((push.approach <= 0) | np.r_[False, np.diff(push.approach) <= 0])) + 1
        raise InputError(f"{path}: {approach}: must be positive and increase from row to row "
                         f"(row {row})")
    if np.any(push.force <= 0):
        raise InputError(f"{path}: {force}: must be positive (row "
                         f"{int(np.argmax(push.force <= 0)) + 1})")
    scene = _scene(path)
    g = scene.geometry
    joint = replace(scene.joint, length=length if length is not None else 2 * g.bore_radius)
    return Curve(path.parent.name, push.approach, push.force, push.half_angle, joint,
                 g.housing_radius / g.bore_radius, scene.materials.pin == scene.materials.bore)


def _scene(path: Path) -> FemScene:
    """The scene the FE run recorded in the result.json beside the curve."""
    result = path.parent / "result.json"
    if not result.is_file():
        raise InputError(f"{path}: needs the FE run's result.json beside it (the scene's "
                         "geometry and materials)")
    data = load_json(result, "fem")
    if "scene" not in data:
        raise InputError(f"{result}: scene: required key is missing "
                         f"({RUN_AGAIN.format(command='fem')})")
    return validate(FemScene, data["scene"], f"{result}: scene")
