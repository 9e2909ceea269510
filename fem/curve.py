"""The curve files of `pinbore fem`, defined once: curve.csv (one row per converged load step)
and pressure.csv (the contact state of the nodes on the refined arc, at every step). The FE
run writes them through `write` and `write_pressure`; the calibration, the report, the
benchmarks and the tests read them through `read` and `read_pressure`.

Units are SI and every column name carries its unit. The two variants differ in the
resultant columns only:

- 2D (plane strain): forces, torque and work per unit length of the pin, force in N/m
  (force_per_length_N_per_m), torque in N m/m (friction_torque_per_length_N), work in J/m;
- 3D: those of the whole pin (a half model counts twice), force in N (force_N), torque in
  N m, work in J; the half-angle is that of the section at the pin's middle; four more
  columns: the hub's tilt (tilt_deg), the hub's moment on the pin about the tilt axis
  through the bore's mid-plane centre (tilt_moment_N_m, positive along a positive tilt: the
  end z = length turned towards the load; fem.scene.FemScene.tilt_axis), the axial position
  of the force's resultant on the bore's axis (resultant_z_m = length/2 + M/F; nan at a
  step without force), and the
  axial length of the pin in contact (contact_length_m); pressure.csv adds the axial position
  z_m and the axial shear.

Both variants carry the plastic work of each step (J/m or J), the largest equivalent plastic
strain so far, and the residual approach (m): on the last step of an unloading the approach
at which the hub force returned to zero, nan on the other steps (nan, undefined, is the one
non-finite value a file may hold, here and in resultant_z_m).

Columns added by later versions (the plastic work of each step, the largest equivalent plastic
strain, the residual approach after an unloading) may be missing from a file written before
them: the reader fills them with their `absent` value (0, 0 and nan: an elastic push).

A reader refuses a file as one InputError line that names the file and what is wrong: a
header that is neither variant (a missing, unknown or repeated column, as a file of another
version of pinbore has), a row of the wrong length, a cell that is not a finite number, or a
stage that is not one of STAGES.
"""

import csv
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.core.scene import RUN_AGAIN

# radial approach; hub turned; pushed across; tilted; moved back to zero force; pushed again
STAGES = ("push", "rotate", "slide", "tilt", "unload", "reload")
UNLOAD, RELOAD = STAGES[4:]


def stage(point) -> str:
    """The stage of a load-programme point (approach m, rotation rad, tangential push m,
    tilt rad)."""
    push, rotate, slide, tilt = STAGES[:4]
    return rotate if point[1] else (slide if point[2] else (tilt if point[3] else push))


@dataclass(frozen=True)
class Column:
    """One column of a file: its name in the header (with the unit), the SI unit, what its
    cells hold (int, float or str) and how a float is written (a format spec)."""

    name: str
    unit: str          # "1": a count or a fraction; "": a name
    kind: type
    format: str = ""   # ints and names are written as they are
    choices: tuple[str, ...] = ()   # the names a str column may hold (empty: any)
    undefined_ok: bool = False       # a float column that may hold nan (undefined, not lost)
    absent: float | None = None      # a column added later: its value in files without it

    def cell(self, value):
        return format(value, self.format) if self.format else value

    def parse(self, text: str, where: str):
        """The value of a cell, or one InputError line (`where`: file, column and row)."""
        if self.kind is str:
            if self.choices and text not in self.choices:
                raise InputError(f"{where}: {text!r} is not one of {', '.join(self.choices)}")
            return text
        try:
            value = self.kind(text)
        except ValueError:
            kind = "an integer" if self.kind is int else "a number"
            raise InputError(f"{where}: {text!r} is not {kind}") from None
        if not math.isfinite(value) and not (self.undefined_ok and math.isnan(value)):
            raise InputError(f"{where}: {value} is not finite")
        return value


def _float(name: str, unit: str, spec: str = ".9e") -> Column:
    return Column(name, unit, float, spec)


@dataclass(frozen=True)
class Curve:
    """The columns of a curve.csv as arrays, one entry per converged step, in the order of
    the file's columns; `dim` tells the variant (2: per unit length, 3: whole pin)."""

    path: Path
    dim: int
    step: np.ndarray               # 1, 2, ... in the order of the load programme
    stage: np.ndarray              # push, rotate or slide (STAGES)
    approach: np.ndarray           # m, hub displacement along the load beyond first touch
    rotation: np.ndarray           # deg, hub rotation
    tangential_push: np.ndarray    # m, hub displacement across the load
    force: np.ndarray              # hub reaction along the load: 2D N/m, 3D N
    tangential_force: np.ndarray   # hub reaction across the load: 2D N/m, 3D N
    friction_torque: np.ndarray    # friction torque on the pin: 2D N m/m, 3D N m
    half_angle: np.ndarray         # deg, contact half-angle
    stick_fraction: np.ndarray     # of the touching nodes, those that stick
    dissipated_work: np.ndarray    # friction work so far: 2D J/m, 3D J
    plastic_work: np.ndarray       # plastic work of this step: 2D J/m, 3D J (0: elastic)
    max_plastic_strain: np.ndarray  # the largest equivalent plastic strain so far
    residual_approach: np.ndarray  # m, on the last step of an unloading: the approach at
                                   # which the force returned to zero (nan on other steps)
    newton_iterations: np.ndarray  # Newton iterations of the step
    uzawa_iterations: np.ndarray   # augmented-Lagrangian updates of the step
    gap_violation: np.ndarray      # m, the largest penetration left
    tilt: np.ndarray | None = None            # deg, hub tilt (3D)
    tilt_moment: np.ndarray | None = None     # N m, hub moment about the tilt axis (3D)
    resultant_z: np.ndarray | None = None     # m, axial position of the resultant (3D)
    contact_length: np.ndarray | None = None  # m, axial length in contact (3D)

    @property
    def points(self) -> int:
        return self.step.size

    def only(self, name: str) -> "Curve":
        """The rows of one stage (push, rotate, slide or tilt)."""
        keep = self.stage == name
        return replace(self, **{f: getattr(self, f)[keep] for f in _fields(Curve)
                                if getattr(self, f) is not None})


_SHARED = {"step": Column("step", "1", int), "stage": Column("stage", "", str, choices=STAGES),
           "approach": _float("approach_m", "m"), "rotation": _float("rotation_deg", "deg"),
           "tangential_push": _float("tangential_push_m", "m"),
           "half_angle": _float("half_angle_deg", "deg", ".6f"),
           "stick_fraction": _float("stick_fraction", "1", ".4f"),
           "newton_iterations": Column("newton_iterations", "1", int),
           "uzawa_iterations": Column("uzawa_iterations", "1", int),
           "gap_violation": _float("gap_violation_m", "m", ".3e"),
           "max_plastic_strain": Column("max_plastic_strain", "1", float, ".6e", absent=0.0),
           "residual_approach": Column("residual_approach_m", "m", float, ".9e",
                                       undefined_ok=True, absent=math.nan)}
_RESULTANTS = {
    2: {"force": _float("force_per_length_N_per_m", "N/m"),
        "tangential_force": _float("tangential_force_per_length_N_per_m", "N/m"),
        "friction_torque": _float("friction_torque_per_length_N", "N m/m"),
        "dissipated_work": _float("dissipated_work_J_per_m", "J/m"),
        "plastic_work": Column("plastic_work_J_per_m", "J/m", float, ".9e", absent=0.0)},
    3: {"force": _float("force_N", "N"), "tangential_force": _float("tangential_force_N", "N"),
        "friction_torque": _float("friction_torque_N_m", "N m"),
        "dissipated_work": _float("dissipated_work_J", "J"),
        "plastic_work": Column("plastic_work_J", "J", float, ".9e", absent=0.0),
        "tilt": _float("tilt_deg", "deg"), "tilt_moment": _float("tilt_moment_N_m", "N m"),
        "resultant_z": Column("resultant_z_m", "m", float, ".9e", undefined_ok=True),  # nan: F = 0
        "contact_length": _float("contact_length_m", "m")},
}


def _fields(kind) -> list[str]:
    """The column fields of Curve or Pressure, in the order of the file's columns."""
    return [f.name for f in fields(kind) if f.name not in ("path", "dim")]


# dim -> field of Curve -> its column
COLUMNS = {dim: {f: (_RESULTANTS[dim] | _SHARED)[f] for f in _fields(Curve)
                 if f in _RESULTANTS[dim] | _SHARED} for dim in (2, 3)}


@dataclass(frozen=True)
class Pressure:
    """The columns of a pressure.csv: per step, the nodes of the refined arc sorted by angle
    from the load (3D: by z, then angle). 2D has no z and no axial shear (None)."""

    path: Path
    dim: int
    step: np.ndarray
    angle: np.ndarray                # deg, from the load direction
    z: np.ndarray | None             # m, 3D: axial position on the untilted pin
    pressure: np.ndarray             # Pa, contact pressure
    shear: np.ndarray                # Pa, shear on the bore along +theta
    shear_axial: np.ndarray | None   # Pa, 3D: shear on the bore along +z
    state: np.ndarray                # open, stick or slip


_PRESSURE = {"step": Column("step", "1", int), "angle": _float("angle_deg", "deg", ".6f"),
             "z": _float("z_m", "m"), "pressure": _float("pressure_Pa", "Pa"),
             "shear": _float("shear_Pa", "Pa"), "shear_axial": _float("shear_axial_Pa", "Pa"),
             "state": Column("state", "", str)}
PRESSURE_COLUMNS = {dim: {f: _PRESSURE[f] for f in _fields(Pressure)
                          if dim == 3 or f not in ("z", "shear_axial")} for dim in (2, 3)}


def column(dim: int, field: str) -> Column:
    """The curve.csv column of a Curve field in the 2D or 3D variant."""
    return COLUMNS[dim][field]


def write(path: Path, dim: int, rows: Iterable[Mapping]) -> None:
    """curve.csv of a 2D or 3D run; a row maps every field of Curve (but path and dim) to
    its value in the units of its column."""
    _write(path, COLUMNS[dim], rows)


def write_pressure(path: Path, dim: int, rows: Iterable[Mapping]) -> None:
    """pressure.csv of a 2D or 3D run; a row maps the fields of Pressure to values."""
    _write(path, PRESSURE_COLUMNS[dim], rows)


def read(path) -> Curve:
    """Every row of a curve.csv, checked (see the module docstring)."""
    path = Path(path)
    dim, values = _read(path, COLUMNS)
    return Curve(path, dim, **values)


def read_pressure(path) -> Pressure:
    """Every row of a pressure.csv, checked (see the module docstring)."""
    path = Path(path)
    dim, values = _read(path, PRESSURE_COLUMNS)
    return Pressure(path, dim, **({"z": None, "shear_axial": None} | values))


def _write(path: Path, columns: dict[str, Column], rows) -> None:
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow([c.name for c in columns.values()])
        for row in rows:
            out.writerow([c.cell(row[field]) for field, c in columns.items()])


def _read(path: Path, variants: dict[int, dict[str, Column]],
          command: str = "fem") -> tuple[int, dict]:
    """The variant (dim) a file's header names and its columns as arrays by field (a file
    that does not fit names `pinbore <command>` to run again)."""
    try:
        with open(path, newline="") as f:
            lines = [row for row in csv.reader(f) if row]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if not lines:
        raise InputError(f"{path}: empty file, not even a header line")
    header, rows = lines[0], lines[1:]
    dim = _variant(path, header, variants, command)
    at = {name: i for i, name in enumerate(header)}
    for i, row in enumerate(rows, start=1):
        if len(row) != len(header):
            raise InputError(f"{path}: row {i}: {len(row)} cells, the header names {len(header)}")
    return dim, {field: np.array([c.parse(row[at[c.name]], f"{path}: {c.name}: row {i}")
                                  for i, row in enumerate(rows, start=1)], dtype=c.kind)
                 if c.name in at else np.full(len(rows), c.absent, dtype=c.kind)
                 for field, c in variants[dim].items()}


def _variant(path: Path, header: list[str], variants: dict[int, dict[str, Column]],
             command: str = "fem") -> int:
    """The dim whose columns the header names (in any order), or one InputError line on the
    first difference from the nearest variant."""
    repeated = [name for i, name in enumerate(header) if name in header[:i]]
    if repeated:
        raise InputError(f"{path}: {repeated[0]}: the column appears twice")
    differences = {}
    for dim, columns in variants.items():
        names = [c.name for c in columns.values()]
        differences[dim] = ([c for c in columns.values()
                             if c.name not in header and c.absent is None],
                            [name for name in header if name not in names])
        if not any(differences[dim]):
            return dim
    missing, unknown = min(differences.values(), key=lambda d: len(d[0]) + len(d[1]))
    again = RUN_AGAIN.format(command=command)
    for c in missing:   # an unknown column named like a missing one: another unit
        alike = [name for name in unknown if name.split("_")[0] == c.name.split("_")[0]]
        if alike:
            raise InputError(f"{path}: {alike[0]}: units do not match; expected {c.name} "
                             f"({c.unit}) ({again})")
    if missing:
        raise InputError(f"{path}: {missing[0].name}: required column is missing ({again})")
    raise InputError(f"{path}: {unknown[0]}: unknown column ({again})")
