"""wear.csv, the worn profiles of a journal and its bore that `pinbore wear` writes and a
mechanism's revolute clearance joint (its `wear_file`) and an FE scene (`geometry.wear_file`)
run on, defined once: per angle of each surface's own frame (deg, evenly spaced from -180) the
depth worn from the bore and from the pin (m). Read back checked: a file that does not fit is
one InputError line naming it. Between its angles a profile is the uniform Catmull-Rom spline
through its points (`spline`), the curve the compiled core's worn joint interpolates
(cpp/mechanism/worn.h) and the FE meshes and contacts.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError

HEADER = "angle_deg,bore_depth_m,pin_depth_m"
MAX_DEPTH = 1e-2   # m: a worn depth beyond a centimetre is no wear of a joint


@dataclass(frozen=True)
class Profiles:
    """The worn depths (m) of the bore (in the bearing body's frame) and of the pin (in the
    journal body's) at the angles (deg) evenly spaced from -180."""

    angle_deg: np.ndarray
    bore: np.ndarray
    pin: np.ndarray


def angles(points: int) -> np.ndarray:
    """`points` angles (deg) evenly spaced from -180."""
    return -180.0 + 360.0 * np.arange(points) / points


def spline(points: np.ndarray, angle) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A periodic profile (its `points` at the angles evenly spaced from -pi) at the angles
    `angle` (rad): its value, slope and curvature (per rad, per rad^2) on the uniform
    Catmull-Rom spline through its points (C1, cubic between two points), the interpolation
    of cpp/mechanism/worn.h (worn_depth); tests/test_wear.py checks the two agree."""
    points = np.asarray(points, dtype=float)
    n = points.size
    step = 2 * np.pi / n
    x = np.mod(np.asarray(angle, dtype=float) + np.pi, 2 * np.pi) / step
    i = np.minimum(np.floor(x).astype(int), n - 1)
    t = x - i
    p0, p1, p2, p3 = (points[(i + j) % n] for j in (-1, 0, 1, 2))
    c1, c2, c3 = p2 - p0, 2 * p0 - 5 * p1 + 4 * p2 - p3, 3 * p1 - p0 - 3 * p2 + p3
    return (0.5 * (2 * p1 + t * (c1 + t * (c2 + t * c3))),
            0.5 * (c1 + t * (2 * c2 + 3 * t * c3)) / step,
            (c2 + 3 * t * c3) / step**2)


def write(path: Path, profiles: Profiles) -> None:
    rows = [HEADER] + [f"{a:.6f},{b:.9e},{p:.9e}"
                       for a, b, p in zip(profiles.angle_deg, profiles.bore, profiles.pin)]
    Path(path).write_text("\n".join(rows) + "\n")


def read(path, source: str | None = None) -> Profiles:
    """The profiles of a wear.csv, checked: its header, at least 3 rows of numbers, the
    angles evenly spaced from -180 deg, the depths finite, from 0 to MAX_DEPTH."""
    source = str(path) if source is None else source
    try:
        lines = Path(path).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{source}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if not lines or lines[0].strip() != HEADER:
        raise InputError(f"{source}: not a wear.csv (its header must be {HEADER}; written by "
                         "pinbore wear)")
    try:
        values = np.array([[float(x) for x in line.split(",")] for line in lines[1:] if line.strip()])
    except ValueError:
        raise InputError(f"{source}: a row is not three numbers (written by pinbore wear?)") from None
    if values.ndim != 2 or values.shape[1] != 3 or values.shape[0] < 3:
        raise InputError(f"{source}: needs three columns and at least 3 rows")
    if not np.allclose(values[:, 0], angles(values.shape[0]), atol=1e-5):
        raise InputError(f"{source}: angle_deg must be evenly spaced from -180 (as pinbore wear "
                         "writes it)")
    depths = values[:, 1:]
    if not np.all(np.isfinite(depths)) or depths.min() < 0 or depths.max() > MAX_DEPTH:
        raise InputError(f"{source}: bore_depth_m, pin_depth_m: must be finite, from 0 to "
                         f"{MAX_DEPTH:g} m")
    return Profiles(values[:, 0], values[:, 1], values[:, 2])
