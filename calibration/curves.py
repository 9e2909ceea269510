"""FE load-approach curves as the calibration reads them, checked before any fit."""

import csv
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import Joint
from pinbore.core.errors import InputError
from pinbore.core.scene import validate

APPROACH, FORCE, ANGLE = "approach_m", "force_per_length_N_per_m", "half_angle_deg"
STAGE = "stage"  # push, rotate or slide: the calibration reads the push


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
    """Read the radial push of DIR/curve.csv and the scene in DIR/result.json. `length` (m)
    is the axial length given to laws that need one; None takes the bore diameter."""
    path = Path(path)
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
            header = reader.fieldnames or []
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: cannot read curve file ({err})") from None
    _check_columns(path, header)
    rows = [row for row in rows if row.get(STAGE, "push") == "push"]
    if len(rows) < min_points:
        raise InputError(f"{path}: {len(rows)} points; a fit of 2 parameters needs at least "
                         f"{min_points}")
    approach, force = (_column(path, rows, key) for key in (APPROACH, FORCE))
    if np.any(approach <= 0) or np.any(np.diff(approach) <= 0):
        row = int(np.argmax((approach <= 0) | np.r_[False, np.diff(approach) <= 0])) + 1
        raise InputError(f"{path}: {APPROACH}: must be positive and increase from row to row "
                         f"(row {row})")
    if np.any(force <= 0):
        raise InputError(f"{path}: {FORCE}: must be positive (row {int(np.argmax(force <= 0)) + 1})")
    scene = _scene(path)
    g = scene.geometry
    joint = replace(scene.joint, length=length if length is not None else 2 * g.bore_radius)
    angle = _column(path, rows, ANGLE) if ANGLE in header else None
    return Curve(path.parent.name, approach, force, angle, joint,
                 g.housing_radius / g.bore_radius, scene.materials.pin == scene.materials.bore)


def _check_columns(path, header) -> None:
    for key, unit in ((APPROACH, "m"), (FORCE, "N/m")):
        if key in header:
            continue
        stem = key.split("_")[0]
        others = [h for h in header if h.startswith(stem)]
        if others:
            raise InputError(f"{path}: {others[0]}: units do not match; calibration reads 2D "
                             f"curves with {key} ({unit})")
        raise InputError(f"{path}: {key}: required column is missing")


def _column(path, rows, key) -> np.ndarray:
    values = []
    for i, row in enumerate(rows, start=1):
        try:
            value = float(row[key])
        except (TypeError, ValueError):
            raise InputError(f"{path}: {key}: row {i}: {row[key]!r} is not a number") from None
        if not math.isfinite(value):
            raise InputError(f"{path}: {key}: row {i}: {value} is not finite")
        values.append(value)
    return np.array(values)


def _scene(path: Path) -> FemScene:
    """The scene the FE run recorded in the result.json beside the curve."""
    result = path.parent / "result.json"
    try:
        data = json.loads(result.read_text())["scene"]
    except (OSError, ValueError, KeyError):
        raise InputError(f"{path}: needs the FE run's result.json beside it (the scene's "
                         "geometry and materials)") from None
    return validate(FemScene, data, str(result))
