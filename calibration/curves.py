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
    section: tuple | None = None   # the plane section: radii, housing and hub radii, materials


@dataclass(frozen=True)
class Curve3D:
    """One 3D FE curve: per step the approach (m), tilt (rad), force (N) and tilting moment
    (N m) about the bore's mid-plane centre; the joint (its length: that given to the
    per-length laws that need one), the bore's length (m), whether the pin runs on beyond
    the bore, the edge relief (length, depth) (m) or None, and the materials pair's name."""

    name: str
    path: Path                # the curve.csv (pressure.csv beside it)
    approach: np.ndarray
    tilt: np.ndarray
    force: np.ndarray
    moment: np.ndarray
    joint: Joint
    length: float
    runs_on: bool
    relief: tuple[float, float] | None
    materials: str
    section: tuple | None = None   # the plane section: radii, housing and hub radii, materials


def read(path, length: float | None) -> Curve | Curve3D:
    """A curve.csv of either kind: 2D (read_curve) or 3D (read_curve_3d)."""
    fe = fe_curve.read(path)
    return read_curve(path, length, fe=fe) if fe.dim == 2 else read_curve_3d(path, length, fe=fe)


def read_all(paths, length: float | None) -> list:
    """Every curve of `paths` (read), none given twice: the same file twice, or two runs with
    the same steps (a copy) would weigh one run double in a fit."""
    curves, seen = [], {}
    for path in paths:
        curve = read(path, length)
        fingerprint = (type(curve).__name__, curve.approach.tobytes(), curve.force.tobytes())
        if fingerprint in seen:
            raise InputError(f"{path}: the same curve as {seen[fingerprint]} (the same run given "
                             "twice); give each FE run once")
        seen[fingerprint] = path
        curves.append(curve)
    return curves


def read_curve_3d(path, length: float | None, min_points: int = 3, fe=None) -> Curve3D:
    """Every step of a 3D DIR/curve.csv with the tilt columns, and the scene in
    DIR/result.json; `length` as in read_curve."""
    path = Path(path)
    fe = fe_curve.read(path) if fe is None else fe
    if fe.points < min_points:
        raise InputError(f"{path}: {fe.points} points; a fit of 2 parameters needs at least "
                         f"{min_points}")
    for key in ("rotation", "tangential_push"):
        if np.any(getattr(fe, key) != 0):
            raise InputError(f"{path}: {fe_curve.column(3, key).name}: the 3D calibration reads "
                             "push and tilt steps only")
    if np.any(fe.approach <= 0) or np.any(fe.force <= 0):
        row = int(np.argmax((fe.approach <= 0) | (fe.force <= 0))) + 1
        raise InputError(f"{path}: {fe_curve.column(3, 'approach').name}, "
                         f"{fe_curve.column(3, 'force').name}: must be positive (row {row})")
    scene = _scene(path, fe)
    g, m = scene.geometry, scene.materials
    if g.tilt_deg:
        raise InputError(f"{path}: geometry.tilt_deg: the 3D calibration reads the tilt as a load "
                         "(load.tilt_deg); a fixed tilt of the pin moves the origin of the approach")
    joint = replace(scene.joint, length=length if length is not None else 2 * g.bore_radius)
    relief = None if g.relief is None else (g.relief.length, g.relief.depth)
    materials = f"E{m.pin.E:.3g}_nu{m.pin.nu:g}_in_E{m.bore.E:.3g}_nu{m.bore.nu:g}"
    return Curve3D(path.parent.name, path, fe.approach, np.radians(fe.tilt), fe.force, fe.tilt_moment,
                   joint, g.length, g.pin_overhang > 0, relief, materials, section_of(scene))


def read_curve(path, length: float | None, min_points: int = 3, fe=None) -> Curve:
    """Read the radial push of DIR/curve.csv (a 2D curve: forces per unit length, N/m) and
    the scene in DIR/result.json. `length` (m) is the axial length given to laws that need
    one; None takes the bore diameter."""
    path = Path(path)
    fe = fe_curve.read(path) if fe is None else fe
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
    scene = _scene(path, fe)
    g = scene.geometry
    joint = replace(scene.joint, length=length if length is not None else 2 * g.bore_radius)
    return Curve(path.parent.name, push.approach, push.force, push.half_angle, joint,
                 g.housing_radius / g.bore_radius, scene.materials.pin == scene.materials.bore,
                 section_of(scene))


def section_of(scene: FemScene) -> tuple:
    """What makes two runs' plane sections the same: radii of bore, pin, housing and hub
    (m), and both materials (E, nu)."""
    g, m = scene.geometry, scene.materials
    return (g.bore_radius, g.pin_radius, g.housing_radius, g.hub_radius, m.pin.E, m.pin.nu,
            m.bore.E, m.bore.nu)


def _scene(path: Path, fe) -> FemScene:
    """The scene the FE run recorded in the result.json beside the curve, checked against the
    curve: of its dimension, and with every step the run converged (a curve cut short is not
    the run's)."""
    result = path.parent / "result.json"
    if not result.is_file():
        raise InputError(f"{path}: needs the FE run's result.json beside it (the scene's "
                         "geometry and materials)")
    data = load_json(result, "fem")
    if "scene" not in data:
        raise InputError(f"{result}: scene: required key is missing "
                         f"({RUN_AGAIN.format(command='fem')})")
    scene = validate(FemScene, data["scene"], f"{result}: scene")
    if scene.geometry.dim != fe.dim:
        raise InputError(f"{result}: scene: geometry.dim = {scene.geometry.dim}, but {path.name} "
                         f"is a {fe.dim}D curve: the result.json of another run")
    converged = data.get("steps_converged")
    if isinstance(converged, int) and fe.points < converged:
        raise InputError(f"{path}: {fe.points} steps, but the run converged {converged} "
                         f"({result.name}): the curve was cut short "
                         f"({RUN_AGAIN.format(command='fem')})")
    return scene
