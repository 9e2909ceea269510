"""From a reduced scene to the arrays of the compiled kernel, with consistent initial
conditions (clearance joints start centred, velocities from the constraints)."""

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.calibration import lawsfile
from pinbore.core.errors import InputError
from pinbore.laws import dissipative, elastic
from pinbore.reduced import kernel
from pinbore.reduced.scene import GROUND, ReducedScene

GRID_POINTS = 600
GRID_LOW = 1e-12       # m, smallest tabulated penetration (power law below)
SPEED_FLOOR = 1e-3     # m/s, smallest impact speed in chi delta'/v0 (grazing contacts)
BLOW_UP_FRACTION = 0.1  # a penetration beyond this fraction of the journal radius stops a run


@dataclass
class Model:
    scene: ReducedScene
    names: list[str]
    minv: np.ndarray
    gravity: np.ndarray
    revolute: np.ndarray
    prismatic: np.ndarray
    drive: np.ndarray
    joints: np.ndarray
    grid_log0: float
    grid_step: float
    tables: np.ndarray
    calibration: dict | None      # the laws file, when a calibrated law is used
    torsion: np.ndarray           # (k, 6): body i, body j, stiffness, damping, free angle, kind
    friction_states: int          # integrator states of LuGre, Dahl (1) and Iwan (2) joints
    y0: np.ndarray

    @property
    def nq(self) -> int:
        return self.minv.size

    def kernel_args(self, speeds=None, latched=None, mode=None, drive=None) -> tuple:
        """The argument tuple of kernel.rhs and kernel.integrate: impact speeds (default: the
        floor), latch flags and contact modes (the integrator's, given here to evaluate a
        recorded step or to continue a run; copied, as the integrator updates them in place),
        and the drive row (default: the scene's)."""
        nj, nt = self.joints.shape[0], self.torsion.shape[0]
        return (self.nq, self.minv, self.gravity, self.revolute, self.prismatic,
                self.drive if drive is None else drive, self.scene.integrator.baumgarte, self.joints,
                np.full(nj, SPEED_FLOOR) if speeds is None else np.array(speeds, float),
                self.grid_log0, self.grid_step, self.tables, self.torsion,
                np.zeros(nt) if latched is None else np.array(latched, float),
                np.zeros(nj, np.int64) if mode is None else np.array(mode, np.int64))

    def elastic_energy(self, joint: int, delta: float) -> float:
        """U(delta) = int_0^delta F_el, exact for the log-log interpolant the dynamics use:
        on a segment F = F_i (d / d_i)^s_i, whose integral is F_i d_i ((d/d_i)^(s_i+1) - 1)/(s_i+1);
        below the grid the first segment's power law continues to 0."""
        if delta <= 0:
            return 0.0
        log_f = self.tables[joint]
        d = np.exp(self.grid_log0 + self.grid_step * np.arange(log_f.size))
        f = np.exp(log_f)
        slope = np.diff(log_f) / self.grid_step
        x = (math.log(delta) - self.grid_log0) / self.grid_step
        i = min(max(int(math.floor(x)), 0), log_f.size - 2)
        below = f[0] * d[0] / (slope[0] + 1)
        whole = f[:i] * d[:i] * ((d[1:i + 1] / d[:i]) ** (slope[:i] + 1) - 1) / (slope[:i] + 1)
        if delta < d[0]:
            return below * (delta / d[0]) ** (slope[0] + 1)
        part = f[i] * d[i] * ((delta / d[i]) ** (slope[i] + 1) - 1) / (slope[i] + 1)
        return float(below + whole.sum() + part)


def build(scene: ReducedScene, source: str, base: Path) -> Model:
    names = [b.name for b in scene.bodies]
    index = {name: i for i, name in enumerate(names)} | {GROUND: -1}
    _check_connected(scene, names)
    minv = np.array([[1 / b.mass, 1 / b.mass, 1 / b.inertia] for b in scene.bodies]).ravel()
    revolute = np.array([[index[j.body_i], *j.point_i, index[j.body_j], *j.point_j]
                         for j in scene.joints if j.type == "revolute"], float).reshape(-1, 6)
    prismatic = np.array([[index[j.body], *j.point, *j.axis_point, math.radians(j.axis_deg),
                           math.radians(scene.bodies[index[j.body]].angle_deg)]
                          for j in scene.joints if j.type == "prismatic"], float).reshape(-1, 7)
    drive = (np.array([index[scene.drive.body], scene.drive.speed_rpm * 2 * math.pi / 60,
                       math.radians(scene.drive.angle0_deg)]) if scene.drive
             else np.array([-1.0, 0.0, 0.0]))
    laws_data = _laws_file(scene, base, source)
    joints, tables, friction_states = [], [], 0
    # penetrations up to a tenth of the journal radius are tabulated; beyond, the run has blown up
    top = max((BLOW_UP_FRACTION * c.journal_radius for c in scene.clearance_joints), default=1.0)
    grid_log0 = math.log(GRID_LOW)
    grid_step = (math.log(top) - grid_log0) / (GRID_POINTS - 1)
    deltas = np.exp(grid_log0 + grid_step * np.arange(GRID_POINTS))
    for c in scene.clearance_joints:
        chi = 0.0 if c.damping_law == "none" else dissipative.HYSTERESIS[c.damping_law](c.restitution)
        code, params, states = friction_block(c.friction)
        state = -1
        if states:
            state, friction_states = 2 * len(minv) + 2 + friction_states, friction_states + states
        joints.append([index[c.bearing_body], *c.bearing_point, index[c.journal_body],
                       *c.journal_point, c.bearing_radius - c.journal_radius, c.bearing_radius,
                       chi, code, *params, state, IMPACT[c.impact], c.restitution, c.rest_speed])
        if c.impact == "continuous":
            force = normal_force(c, deltas, laws_data, source)
            force[deltas > BLOW_UP_FRACTION * c.journal_radius] = np.nan
        else:
            force = np.full(GRID_POINTS, np.nan)   # rigid: no law, never evaluated
        tables.append(np.log(force))
    model = Model(scene, names, minv, np.asarray(scene.gravity, float), revolute, prismatic, drive,
                  np.array(joints, float).reshape(-1, kernel.JOINT_COLUMNS), grid_log0, grid_step,
                  np.array(tables).reshape(len(joints), GRID_POINTS), laws_data,
                  torsion_rows(scene, index), friction_states, np.empty(0))
    model.y0 = initial_state(model)
    return model


IMPACT = {"continuous": kernel.CONTINUOUS, "newton": kernel.NEWTON, "poisson": kernel.POISSON}


def torsion_rows(scene, index) -> np.ndarray:
    """Torsion springs, stops and latches; angles relative to the bodies' initial relative angle."""
    angle = {b.name: math.radians(b.angle_deg) for b in scene.bodies} | {GROUND: 0.0}
    return np.array([[index[t.body_i], index[t.body_j], t.stiffness, t.damping,
                      angle[t.body_j] - angle[t.body_i] + math.radians(t.free_angle_deg),
                      {"spring": kernel.SPRING, "stop": kernel.STOP, "latch": kernel.LATCH}[t.type]]
                     for t in scene.torsion], float).reshape(-1, 6)


def friction_block(f):
    """(kernel law code, 7 parameters, number of integrator states) of a friction table.
    Static laws put their regularisation speeds v0, v1 in the last two parameters."""
    if f is None:
        return kernel.NO_FRICTION, [0.0] * 7, 0
    if f.law == "coulomb_ambrosio":
        return kernel.COULOMB, [f.mu, 0, 0, 0, 0, f.v0, f.v1], 0
    if f.law == "stribeck":
        return kernel.STRIBECK, [f.mu_static, f.mu_min, f.v_min, 0, 0, f.v0, f.v1], 0
    if f.law == "linear":
        return kernel.LINEAR, [f.mu_static, f.alpha, 0, 0, 0, f.v0, f.v1], 0
    if f.law == "lugre":
        return kernel.LUGRE, [f.mu_coulomb, f.mu_static, f.stribeck_speed, f.sigma0, f.sigma1,
                              f.sigma2, 0], 1
    if f.law == "dahl":
        return kernel.DAHL, [f.mu, f.sigma, 0, 0, 0, 0, 0], 1
    return kernel.IWAN, [f.k1, f.k2, f.mu, 0, 0, 0, 0], 2


def normal_force(c, deltas, laws_data, source) -> np.ndarray:
    """Elastic normal force (N) of a clearance joint at the penetrations `deltas`; a
    calibrated law is that of the laws file (`laws_data`, calibration/lawsfile.py) times
    the joint's length."""
    joint = elastic.Joint(c.bearing_radius, c.journal_radius, c.E, c.nu, c.E, c.nu, c.length)
    if c.normal_law == "hertz_point":
        return elastic.hertz_point(deltas, joint)
    if c.normal_law.startswith("calibrated:"):
        name = c.normal_law.split(":", 1)[1]
        fitted = laws_data.fitted()
        if name not in fitted:
            raise InputError(f"{source}: clearance_joints.normal_law: {c.normal_law!r} is not a "
                             f"fitted law of the laws file; valid: calibrated:{', calibrated:'.join(fitted)}")
        return fitted[name].force(name, deltas, joint) * c.length
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the range is enforced by the table (NaN beyond it)
        return elastic.PUBLISHED[c.normal_law](deltas, joint) * c.length


def laws_path(scene, base: Path) -> Path | None:
    """Where the scene's laws file is (relative to the scene's folder `base`), if it has one."""
    if scene.laws_file is None:
        return None
    return (base / scene.laws_file) if not Path(scene.laws_file).is_absolute() else Path(scene.laws_file)


def _laws_file(scene, base: Path, source: str) -> lawsfile.LawsFile | None:
    """The scene's laws file, validated."""
    path = laws_path(scene, base)
    return None if path is None else lawsfile.read(path, f"{source}: laws_file: {path}")


def _check_connected(scene, names) -> None:
    """Every body must be linked to the others (through joints, clearance joints, the ground)."""
    links = {name: set() for name in names + [GROUND]}
    pairs = [(j.body_i, j.body_j) if j.type == "revolute" else (j.body, GROUND) for j in scene.joints]
    pairs += [(c.bearing_body, c.journal_body) for c in scene.clearance_joints]
    pairs += [(t.body_i, t.body_j) for t in scene.torsion]
    if scene.drive:
        pairs.append((scene.drive.body, GROUND))
    for a, b in pairs:
        links[a].add(b)
        links[b].add(a)
    start = names[0]
    seen, todo = {start}, [start]
    while todo:
        for other in links[todo.pop()] - seen:
            seen.add(other)
            todo.append(other)
    lost = [n for n in names if n not in seen]
    if lost:
        raise InputError(f"bodies: {', '.join(lost)} not connected to {start} by any joint "
                         "(disconnected mechanism)")


def _as_revolutes(model: Model, starts=("ideal", "free")) -> np.ndarray:
    """Ideal revolutes plus the clearance joints whose start is in `starts`, closed."""
    keep = [j for j, c in enumerate(model.scene.clearance_joints) if c.start in starts]
    closed = model.joints[keep][:, [0, 1, 2, 3, 4, 5]]
    return np.vstack([model.revolute, closed]) if closed.size else model.revolute


def project(q, qd, revolute, prismatic, drive, minv, t=0.0):
    """The nearest consistent state: positions moved least onto Phi(q, t) = 0 (Gauss-Newton),
    velocities projected onto Phi_q q' = -Phi_t with least change in kinetic-energy norm.
    Returns (q, q', largest remaining position gap)."""
    q, qd = q.copy(), qd.copy()
    zero = np.zeros_like(q)
    gap = 0.0
    for _ in range(50):
        jac, _, phi, _ = kernel.constraints(t, q, zero, revolute, prismatic, drive, 0.0)
        gap = np.max(np.abs(phi), initial=0.0)
        if jac.shape[0] == 0 or gap < 1e-14:
            break
        q -= jac.T @ np.linalg.lstsq(jac @ jac.T, phi, rcond=None)[0]
    jac, _, _, phi_t = kernel.constraints(t, q, zero, revolute, prismatic, drive, 0.0)
    if jac.shape[0]:
        scaled = jac * minv
        qd -= scaled.T @ np.linalg.lstsq(scaled @ jac.T, jac @ qd + phi_t, rcond=None)[0]
    return q, qd, gap


def initial_state(model: Model) -> np.ndarray:
    """Positions satisfying the ideal joints with the journals centred (least change from the
    scene's guesses), and the scene's velocities projected onto Phi_q q' = -Phi_t (least change
    in kinetic-energy norm) of the ideal joints and the clearance joints that start "ideal"
    ("placed" journals keep their positions)."""
    q = np.array([[*b.position, math.radians(b.angle_deg)] for b in model.scene.bodies]).ravel()
    qd = np.array([[*b.velocity, b.omega] for b in model.scene.bodies]).ravel()
    q, _, gap = project(q, qd, _as_revolutes(model), model.prismatic, model.drive, model.minv)
    if gap >= 1e-14:
        raise InputError("joints: the bodies cannot be placed so that every joint closes "
                         f"(largest gap {gap:.3g} m)")
    _, qd, _ = project(q, qd, _as_revolutes(model, ("ideal",)), model.prismatic, model.drive,
                       model.minv)
    return np.concatenate([q, qd, [0.0, 0.0], np.zeros(model.friction_states)])
