"""wear.csv, the worn profiles of a journal and its bore that `pinbore wear` writes and a
mechanism's revolute clearance joint runs on (its `wear_file`), defined once: per angle of
each surface's own frame (deg, evenly spaced from -180) the depth worn from the bore and from
the pin (m). Read back checked: a file that does not fit is one InputError line naming it.
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
