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


NODE = math.radians(5)   # rad: the grid of load directions in the bore's and in the pin's frame
RATIO = 2.0              # between the loads a node is solved under, F_top RATIO^j (F_top: the FE run's top)
LIGHTEST = -8            # the least j solved; lighter loads' pressure linear from it to none
TINY = 1e-9              # a share of a node below it (rounding) is none
NARROW = 3               # points of the compliance's grid: a contact patch on fewer is not resolved


@dataclass(frozen=True)
class Blend:
    """A weighted sum of pressure tables on the same angles, with PressureTable's calls."""

    tables: tuple
    weights: tuple

    @property
    def angles(self) -> np.ndarray:
        return self.tables[0].angles

    @property
    def reach(self) -> float:
        return max(t.reach for t in self.tables)

    def at(self, force: float) -> np.ndarray:
        return sum(w * t.at(force) for t, w in zip(self.tables, self.weights))

    def integral_at(self, force: float) -> np.ndarray:
        return sum(w * t.integral_at(force) for t, w in zip(self.tables, self.weights))


@dataclass(frozen=True)
class WornPressure:
    """worn_tables' answer: per recorded step a table of each surface (None out of contact),
    the loads solved, and how many of them pressed no patch of NARROW points or more (the
    contact narrower than the compliance's grid resolves)."""

    bore: list
    pin: list
    solves: int
    narrow: int


def worn_tables(conformal, table: PressureTable, force_per_length, bore_angle, pin_angle) -> WornPressure:
    """The pressure of the worn joint (fem.compliance.Conformal: the FE's compliance on the
    worn surfaces) for each recorded step, on each surface: a table per step (None out of
    contact) for wear.profile.worn_depth (WornPressure). Which parts of the
    two worn surfaces meet is set by the load's direction in the bore's frame and in the
    pin's (`bore_angle`, `pin_angle`): the joint is solved on a grid of both, NODE apart,
    the pin turned by their difference, under the fixed loads F_top RATIO^j (F_top: `table`'s
    top load; j from the load at or below its steps' lightest, not below LIGHTEST, to the one
    at or above their heaviest). A node's bore table holds the pressure on the bore's arc
    against the angle from the node's direction in the bore's frame; its pin table the
    pressure on the pin's arc against the arc length from its direction in the pin's frame
    (as an angle about the bore's centre: wear.profile's convention). A step's tables blend
    its four nodes' bilinearly in its two directions: the pressure moves as continuously
    with the history as the history moves with the wear (cycle jumping differences it)."""
    forces = np.asarray(force_per_length, float)
    on = np.flatnonzero(forces > 0)
    count = int(round(2 * math.pi / NODE))
    corners = []   # per frame: (the lower node, the upper node's share) of every step
    for angle in (bore_angle, pin_angle):
        position = np.mod(np.asarray(angle, float) + math.pi, 2 * math.pi) / NODE
        corners.append((np.floor(position).astype(int) % count, position - np.floor(position)))
    (ib, sb), (ip, sp) = corners
    # a step's share of a node below TINY (a step on a node, to rounding) goes to the others
    sb, sp = (np.where(x < TINY, 0.0, np.where(x > 1 - TINY, 1.0, x)) for x in (sb, sp))
    shares = {}   # node -> [(step, its bilinear weight)]
    for db, wb in ((0, 1.0 - sb), (1, sb)):
        for dp, wp in ((0, 1.0 - sp), (1, sp)):
            w = wb * wp
            for k in on[w[on] > 0]:
                shares.setdefault(((ib[k] + db) % count, (ip[k] + dp) % count), []).append((k, w[k]))
    grid = -math.pi + conformal.spacing * np.arange(conformal.n + 1)
    scale = table.pin_radius / table.bore_radius   # the pin's arc as an angle about the bore's centre
    top = float(table.forces[-1])
    nodes, solves, narrow = {}, 0, 0
    for (i, j), members in shares.items():
        loads = forces[[k for k, _ in members]]
        first = max(LIGHTEST, math.floor(math.log(loads.min() / top, RATIO)))
        last = max(first, math.ceil(math.log(loads.max() / top, RATIO) - 1e-9))
        levels = top * RATIO ** np.arange(first, last + 1, dtype=float)
        direction, pin_direction = -math.pi + i * NODE, -math.pi + j * NODE
        turn = direction - pin_direction
        rows = {"bore": [np.zeros(grid.size)], "pin": [np.zeros(grid.size)]}
        for load in levels:   # each alone (Conformal.loaded: from the push along the load)
            p, theta, _, _, push = conformal.loaded(load, direction, turn)
            solves, narrow = solves + 1, narrow + (_widest_patch(p > 0) < NARROW)
            force = p * conformal.bore_radius * conformal.spacing   # each point's (N/m)
            rows["bore"].append(_spread(theta - direction, force, grid, conformal.bore_radius))
            beta = conformal.beta[conformal.facing(push, turn)]   # the points' angles in the pin's frame
            offset = np.mod(beta - pin_direction + math.pi, 2 * math.pi) - math.pi
            rows["pin"].append(_spread(scale * offset, force, grid, conformal.bore_radius))
        load_axis = np.concatenate([[0.0], levels])
        nodes[(i, j)] = {name: PressureTable(load_axis, grid, np.array(r), table.pin_radius, table.bore_radius)
                         for name, r in rows.items()}
    out = {"bore": [None] * forces.size, "pin": [None] * forces.size}
    for node, members in shares.items():
        for k, w in members:
            for name in out:
                out[name][k] = (out[name][k] or []) + [(nodes[node][name], w)]
    for name, per_step in out.items():
        out[name] = [None if m is None else Blend(*zip(*m)) for m in per_step]
    return WornPressure(out["bore"], out["pin"], solves, narrow)


def _widest_patch(pressed: np.ndarray) -> int:
    """The most consecutive pressed points."""
    edges = np.diff(np.concatenate([[0], pressed.astype(int), [0]]))
    return int(np.max(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1), initial=0))


def _spread(alpha, force, grid, radius: float) -> np.ndarray:
    """The pressure (Pa) on the evenly spaced `grid` (rad, from -pi to pi, its ends one
    angle) of point forces per unit length `force` (N/m) at the angles `alpha` about a centre
    at `radius` (m): each force shared by its two nodes linearly in its place between them,
    so that the pressure's integral (trapezoidal, PressureTable's) is the forces' sum, and
    the pressure moves continuously with the points."""
    n = grid.size - 1
    spacing = 2 * math.pi / n
    position = np.mod(np.asarray(alpha) + math.pi, 2 * math.pi) / spacing
    lower = np.floor(position).astype(int)
    upper_share = position - lower
    row = np.zeros(n)
    np.add.at(row, lower % n, force * (1 - upper_share))
    np.add.at(row, (lower + 1) % n, force * upper_share)
    return np.append(row, row[0]) / (radius * spacing)
