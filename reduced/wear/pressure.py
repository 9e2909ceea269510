"""The contact pressure of a joint under a load, from its FE run (`pinbore fem`, 2D, per unit
length): the nodal pressure of each push step (pressure.csv) against the angle from the
load about the bore's centre (the nodes of the bore's surface), under that step's load per
unit length (curve.csv), on the angles of the run's nodes (zero beyond them, to -pi and pi)."""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.fem import curve as fe_curve

@dataclass(frozen=True)
class PressureTable:
    """p(alpha; F'): the contact pressure (Pa) at the angle alpha from the load about the
    bore's centre (rad, on `angles`, increasing from -pi to pi) under the load per unit length
    F' (N/m, `forces`: 0 first, increasing)."""

    forces: np.ndarray
    angles: np.ndarray
    pressure: np.ndarray          # (forces, angles)
    pin_radius: float             # m, of the FE run
    bore_radius: float            # m

    def __post_init__(self):
        # P(alpha) = integral of p from -pi to alpha, row by row (exact for p linear between
        # the angles): a contact that turns takes the mean of p over the arc it sweeps
        steps = 0.5 * (self.pressure[:, 1:] + self.pressure[:, :-1]) * np.diff(self.angles)
        object.__setattr__(self, "integral", np.concatenate(
            [np.zeros((self.forces.size, 1)), np.cumsum(steps, axis=1)], axis=1))
        # the reach of a contact's pressure (rad): the largest |alpha| of the angles where a
        # step presses and of their neighbours (p is linear between the angles)
        pressed = np.flatnonzero(np.any(self.pressure > 0, axis=0))
        near = np.clip(np.concatenate([pressed - 1, pressed + 1]), 0, self.angles.size - 1)
        object.__setattr__(self, "reach", float(np.abs(self.angles[near]).max()) if pressed.size else 0.0)

    def at(self, force: float) -> np.ndarray:
        """The pressure on `angles` under F' = force (N/m): linear between the FE steps;
        beyond the last one, its profile scaled by the force ratio (extrapolated: the run
        reports how far, wear.run)."""
        return self._blend(self.pressure, force)

    def integral_at(self, force: float) -> np.ndarray:
        """P(alpha) on `angles`, the integral of at(force) from -pi (Pa rad)."""
        return self._blend(self.integral, force)

    def _blend(self, rows: np.ndarray, force: float) -> np.ndarray:
        top = self.forces[-1]
        if force >= top:
            return rows[-1] * (force / top)
        i = int(np.searchsorted(self.forces, force, side="right")) - 1
        a = (force - self.forces[i]) / (self.forces[i + 1] - self.forces[i])
        return (1 - a) * rows[i] + a * rows[i + 1]

    def resultant(self, k: int) -> float:
        """The load per unit length the pressure of step k carries, the integral of
        p cos(alpha) over the bore's surface (N/m): the FE step's own F' where the pressure is
        resolved (a check of the table)."""
        return float(np.trapezoid(self.pressure[k] * np.cos(self.angles), self.angles) * self.bore_radius)


def read(pressure_file: Path, curve_file: Path, source: str) -> PressureTable:
    """The table of a 2D FE run's push steps. One InputError line for a run that is not 2D,
    has no push step, or whose files do not belong together."""
    pressure, curve = fe_curve.read_pressure(pressure_file), fe_curve.read(curve_file)
    if pressure.dim != 2 or curve.dim != 2:
        raise InputError(f"{source}: pressure_file: a 2D FE run (per unit length) is needed, "
                         "not a 3D one")
    push = [int(s) for s, stage in zip(curve.step, curve.stage) if stage == "push"]
    if not push:
        raise InputError(f"{source}: curve_file: no push step (the load of the FE run)")
    force = dict(zip(curve.step.tolist(), curve.force.tolist()))
    nodes = np.unique(np.radians(pressure.angle))
    grid = np.concatenate([[-math.pi], nodes[(nodes > -math.pi) & (nodes < math.pi)], [math.pi]])
    rows, loads = [np.zeros(grid.size)], [0.0]
    for step in push:
        mine = pressure.step == step
        if not mine.any():
            raise InputError(f"{source}: pressure_file: no pressure of step {step} of curve_file "
                             "(the two files are not of one FE run)")
        order = np.argsort(pressure.angle[mine])
        alpha = np.radians(pressure.angle[mine][order])
        rows.append(np.interp(grid, alpha, pressure.pressure[mine][order], left=0.0, right=0.0))
        loads.append(force[step])
    loads = np.array(loads)
    if np.any(np.diff(loads) <= 0):
        raise InputError(f"{source}: curve_file: the push steps' loads do not increase")
    geometry = _geometry(Path(curve_file), source)
    return PressureTable(loads, grid, np.array(rows), *geometry)


def _geometry(curve_file: Path, source: str) -> tuple[float, float]:
    """(pin radius, bore radius) of the FE run, from the result.json beside its curve."""
    from pinbore.core.scene import load_json   # noqa: PLC0415

    data = load_json(curve_file.parent / "result.json", "fem",
                     f"{source}: curve_file's result.json")
    try:
        g = data["scene"]["geometry"]
        radii = float(g["pin_radius"]), float(g["bore_radius"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{source}: curve_file's result.json: no scene geometry (run pinbore "
                         "fem again)") from None
    if g.get("wear_file") is not None:
        raise InputError(f"{source}: curve_file: the FE run of a worn joint (its "
                         "geometry.wear_file); the wear takes the pressure of the new joint's")
    return radii


SECTOR = math.radians(5)   # rad: the load directions a worn joint's pressure is solved along
LEVELS = (1 / 27, 1 / 9, 1 / 3, 1.0)   # of a sector's largest load: the loads it is solved under


def worn_tables(conformal, table: PressureTable, force_per_length, bore_angle, pin_angle,
                weight) -> list:
    """The pressure of the worn joint (fem.compliance.Conformal: the FE's compliance on the
    worn surfaces) for each recorded step: per sector of SECTOR of the load's direction in the
    bore's frame that the steps visit, the joint loaded along the sector's middle by LEVELS
    of its steps' largest load, the pin turned by their mean turn (weighted by `weight`, the
    steps' share of the wear), as a PressureTable on the angles from the load (the FE run's
    radii of `table`); None for a step out of contact."""
    forces = np.asarray(force_per_length, float)
    on = forces > 0
    sector = np.floor((np.asarray(bore_angle) + math.pi) / SECTOR).astype(int)
    turn = np.asarray(bore_angle) - np.asarray(pin_angle)
    grid = -math.pi + conformal.spacing * np.arange(conformal.n + 1)
    out = [None] * forces.size
    for s in np.unique(sector[on]):
        mine = on & (sector == s)
        w = np.asarray(weight)[mine] + 1e-300
        mean_turn = math.atan2(np.sum(w * np.sin(turn[mine])), np.sum(w * np.cos(turn[mine])))
        direction = -math.pi + (s + 0.5) * SECTOR
        top = float(forces[mine].max())
        rows, push = [np.zeros(grid.size)], None
        for level in LEVELS:   # each from the last one's push
            p, theta, _, _, push = conformal.loaded(level * top, direction, mean_turn, push)
            p = conformal.on_bore(p, theta)
            alpha = np.mod(theta - direction + math.pi, 2 * math.pi) - math.pi
            order = np.argsort(alpha)
            rows.append(np.interp(grid, alpha[order], p[order], left=0.0, right=0.0))
        sector_table = PressureTable(top * np.array((0.0,) + LEVELS), grid, np.array(rows),
                                     table.pin_radius, table.bore_radius)
        for k in np.flatnonzero(mine):
            out[k] = sector_table
    return out
