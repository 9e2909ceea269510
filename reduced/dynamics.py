r"""Nonlinear dynamics of periodically driven systems, seen once per driving period.

A `Flow` is what the analyses need of a system: its driving period, a way to advance a state
by whole periods, the state's coordinates (normalised, so that distances mean something) and
a way to perturb a state along them. `MechanismFlow` wraps a driven planar model and
`SpatialMechanismFlow` a driven spatial one; the tests wrap a forced Duffing oscillator the
same way, so every analysis is checked on a system with published behaviour.

- Poincare map (stroboscopic, at the driving period): the first `transient` periods are
  discarded, then `periods` samples are kept. The transient criterion is the count given
  (default 50 periods: for the slider-crank's journal, impacts damp an initial condition in
  a few revolutions; the classification is checked not to change when it is doubled).
- Classification of the samples x_0..x_(N-1): periodic with period p (the smallest p <= 16
  with |x_(i+p) - x_i| <= tol * max |x| for every i); otherwise chaotic if the largest
  Lyapunov exponent is positive, quasi-periodic if not.
- Largest Lyapunov exponent (Benettin et al. 1980 [Benettin1980]): a neighbour at distance d0 is advanced
  with the reference one period at a time, its separation d measured and renormalised back
  to d0; lambda = sum log(d / d0) / (N T). Each trajectory locates its own impacts, so an
  impact that one meets and the other misses shows up as the (finite) jump it is; d0 = 1e-7
  of the coordinates' scale keeps such jumps rare.
- Periodic orbits by shooting: Newton on P^m(x) - x = 0 with the Jacobian of the m-fold map
  by finite differences; its eigenvalues are the Floquet multipliers (stable when all lie
  inside the unit circle).
"""

import math
from dataclasses import dataclass, replace

import numpy as np
from tqdm import tqdm

from pinbore.reduced import kernel, spatial_kernel
from pinbore.reduced.layout import (
    DRIVE_ANGLE, DRIVE_BODY, DRIVE_SPEED, JOINT_BEARING_BODY, JOINT_BEARING_X, JOINT_BEARING_Y,
    JOINT_CLEARANCE, JOINT_JOURNAL_BODY, JOINT_JOURNAL_X, JOINT_JOURNAL_Y)
from pinbore.reduced.model import Model, project
from pinbore.reduced.run import simulate
from pinbore.reduced.spatial_layout import (
    ANGLE, BODY_POS, BODY_ROT, BODY_VEL, CYLINDER, PRIM_BODY_I, PRIM_BODY_J, PRIM_KIND, PRIM_SPEED, SJ_BEARING_AXIS,
    SJ_BEARING_BODY, SJ_BEARING_POINT, SJ_JOURNAL_BODY, SJ_JOURNAL_POINT, SJ_KIND)

MAX_PERIOD = 16


@dataclass
class MechanismState:
    y: np.ndarray           # the kernel's state vector
    speeds: np.ndarray      # impact speeds of the clearance joints
    mode: np.ndarray        # contact modes (held contacts of impulse joints)
    latched: np.ndarray     # latch flags of the torsion elements
    period: int             # periods elapsed since the start


def advanced(flow, state: MechanismState, periods: int, args) -> MechanismState:
    """The state `periods` drive periods on, integrating the flow's model with the kernel
    arguments `args` (their impact speeds, modes and latches updated in place); the
    trajectory is kept in flow.last. An integration that stops is a FloatingPointError."""
    flow.last = simulate(flow.model, state.y, periods * flow.period, args)
    if flow.last.status != kernel.OK:
        raise FloatingPointError(f"the integration stopped at t = {flow.last.t_end:.6g} s "
                                 f"of period {state.period} (status {flow.last.status})")
    return MechanismState(flow.last.states[-1].copy(), args.speeds, args.mode, args.latched,
                          state.period + periods)


class MechanismFlow:
    """A driven reduced model advanced by whole crank periods. Coordinates: positions and
    velocities of every body, the driven angle taken relative to the drive, scaled by the
    smallest clearance c (m) and c omega (m/s)."""

    def __init__(self, model: Model):
        self.model = model
        self.omega = model.drive[DRIVE_SPEED]
        self.period = 2 * math.pi / abs(self.omega)
        self.length = min(model.joints[:, JOINT_CLEARANCE], default=1e-3)
        nq = model.nq
        self.scale = np.concatenate([np.full(nq, self.length), np.full(nq, self.length * abs(self.omega))])
        self.driven = int(model.drive[DRIVE_BODY])
        self.last = None   # the Trajectory of the last advance (for the design study)

    def start(self) -> MechanismState:
        args = self.model.kernel_args()
        return MechanismState(self.model.y0.copy(), args.speeds, args.mode, args.latched, 0)

    def _drive(self, period: int) -> np.ndarray:
        drive = self.model.drive.copy()
        drive[DRIVE_ANGLE] += 2 * math.pi * period * math.copysign(1.0, self.omega)
        return drive

    def advance(self, state: MechanismState, periods: int = 1) -> MechanismState:
        return advanced(self, state, periods, self.model.kernel_args(
            state.speeds, state.latched, state.mode, self._drive(state.period)))

    def coordinates(self, state: MechanismState) -> np.ndarray:
        nq = self.model.nq
        x = state.y[:2 * nq].copy()
        if self.driven >= 0:
            x[3 * self.driven + 2] -= self._drive(state.period)[DRIVE_ANGLE]
        return x / self.scale

    def observed(self, state: MechanismState) -> np.ndarray:
        """What the Poincare map shows: the first clearance joint's journal centre relative to
        its bearing centre (m) and its rate (m/s); without clearance joints, the centre of the
        first body that is not driven."""
        nq = self.model.nq
        q, qd = state.y[:nq], state.y[nq:2 * nq]
        if self.model.joints.shape[0]:
            row = self.model.joints[0]
            points = ((int(row[JOINT_JOURNAL_BODY]), row[JOINT_JOURNAL_X], row[JOINT_JOURNAL_Y], 1.0),
                      (int(row[JOINT_BEARING_BODY]), row[JOINT_BEARING_X], row[JOINT_BEARING_Y], -1.0))
        else:
            body = next(b for b in range(nq // 3) if b != self.driven)
            points = ((body, 0.0, 0.0, 1.0),)
        out = np.zeros(4)
        for body, sx, sy, sign in points:
            x, y = kernel.point(q, body, sx, sy)
            out[:2] += sign * np.array([x, y])
            if body >= 0:
                w = qd[3 * body + 2]
                out[2:] += sign * np.array([qd[3 * body] - w * (y - q[3 * body + 1]),
                                            qd[3 * body + 1] + w * (x - q[3 * body])])
        return out

    def observed_name(self) -> str:
        if self.model.joints.shape[0]:
            return f"journal centre of {self.model.scene.clearance_joints[0].name} relative to its bearing"
        body = next(b for b in range(self.model.nq // 3) if b != self.driven)
        return f"centre of body {self.model.names[body]}"

    def perturb(self, state: MechanismState, dx: np.ndarray) -> MechanismState:
        """The state moved by dx (in coordinates), then made consistent with the ideal joints."""
        model, nq = self.model, self.model.nq
        y = state.y.copy()
        y[:2 * nq] += dx * self.scale
        q, qd, _ = project(y[:nq], y[nq:2 * nq], model.revolute, model.prismatic,
                           self._drive(state.period), model.minv)
        y[:nq], y[nq:2 * nq] = q, qd
        return replace(state, y=y)


class SpatialMechanismFlow:
    """A driven spatial model (reduced.spatial_model) advanced by whole drive periods.

    Coordinates, per body: its centre scaled by the smallest clearance c; its Euler
    parameters p, with the sign that makes the largest in magnitude positive (p and -p are
    one orientation, and a turn of 2 pi changes the sign), scaled by c / (2 k), k the body's
    radius of gyration sqrt(trace J / 3m) (a small turn d theta changes p by d theta / 2 and
    moves a point at k by k d theta); their rates scaled by c omega the same way. The drive
    needs no shift from period to period: its constraint holds the relative angle modulo
    2 pi."""

    def __init__(self, model):
        self.model = model
        drive = model.primitives[model.primitives[:, PRIM_KIND] == ANGLE]
        self.omega = drive[0, PRIM_SPEED]
        self.period = 2 * math.pi / abs(self.omega)
        self.length = min(model.joints[:, JOINT_CLEARANCE], default=1e-3)
        gyration = np.sqrt(np.trace(model.inertia, axis1=1, axis2=2) / (3 * model.masses))
        per_body = np.concatenate([np.full((model.masses.size, 3), 1.0),
                                   np.repeat(0.5 / gyration[:, None], 4, axis=1)], axis=1).ravel()
        self.scale = self.length * np.concatenate([per_body, per_body * abs(self.omega)])
        self.last = None   # the Trajectory of the last advance

    def start(self) -> MechanismState:
        args = self.model.kernel_args()
        return MechanismState(self.model.y0.copy(), args.speeds, args.mode, args.latched, 0)

    def advance(self, state: MechanismState, periods: int = 1) -> MechanismState:
        return advanced(self, state, periods, self.model.kernel_args(state.speeds, state.latched))

    def _signs(self, y) -> np.ndarray:
        """+1, or -1 on the Euler parameters (and their rates) of a body whose largest
        parameter in magnitude is negative."""
        nq = self.model.nq
        signs = np.ones(2 * nq)
        for b in range(self.model.masses.size):
            p = y[7 * b + 3:7 * b + 7]
            if p[np.argmax(np.abs(p))] < 0:
                signs[7 * b + 3:7 * b + 7] = signs[nq + 7 * b + 3:nq + 7 * b + 7] = -1.0
        return signs

    def coordinates(self, state: MechanismState) -> np.ndarray:
        y = state.y[:2 * self.model.nq]
        return y * self._signs(y) / self.scale

    def perturb(self, state: MechanismState, dx: np.ndarray) -> MechanismState:
        """The state moved by dx (in coordinates), then made consistent with the ideal joints
        and the drive (Euler parameters normalised; Gauss-Newton projection)."""
        nq = self.model.nq
        y = state.y.copy()
        y[:2 * nq] += dx * self.scale * self._signs(y)
        args = self.model.kernel_args(state.speeds, state.latched)
        work = spatial_kernel.workspace(args)
        for _ in range(50):
            if not spatial_kernel.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
                break
        return replace(state, y=y)

    def _frame(self):
        """The first clearance joint, and two unit vectors across its bore's axis in the
        bearing body's frame (the body's x axis made normal to the axis, or y if the axis
        lies near x; a ball: x and y)."""
        row = self.model.joints[0]
        if int(row[SJ_KIND]) != CYLINDER:
            return row, np.eye(3)[0], np.eye(3)[1]
        u = row[SJ_BEARING_AXIS:SJ_BEARING_AXIS + 3]
        helper = np.eye(3)[0] if abs(u[0]) < 0.9 else np.eye(3)[1]
        f = helper - (helper @ u) * u
        f /= np.linalg.norm(f)
        return row, f, np.cross(u, f)

    def observed(self, state: MechanismState) -> np.ndarray:
        """The first clearance joint's journal centre relative to its bearing centre (m) and
        its rate (m/s), across the bore (in the bearing body's frame); without clearance
        joints, the centre of the first body that is not driven (x, y global)."""
        args = self.model.kernel_args()
        work = spatial_kernel.workspace(args)
        spatial_kernel.body_states(state.y, args, work)
        if not self.model.joints.shape[0]:
            b = self._free_body()
            return np.array([*work.bodies[b, BODY_POS:BODY_POS + 2],
                             *work.bodies[b, BODY_VEL:BODY_VEL + 2]])
        row, f, g = self._frame()
        bb, bj = int(row[SJ_BEARING_BODY]), int(row[SJ_JOURNAL_BODY])
        pj = spatial_kernel.point_state(work.bodies, bj, tuple(row[SJ_JOURNAL_POINT:SJ_JOURNAL_POINT + 3]))[0]
        pb = spatial_kernel.point_state(work.bodies, bb, tuple(row[SJ_BEARING_POINT:SJ_BEARING_POINT + 3]))[0]
        e = np.subtract(pj, pb)
        v = np.subtract(spatial_kernel.material_velocity(work.bodies, bj, pj),
                        spatial_kernel.material_velocity(work.bodies, bb, pj))
        a = work.bodies[bb, BODY_ROT:BODY_ROT + 9].reshape(3, 3) if bb >= 0 else np.eye(3)
        return np.array([e @ (a @ f), e @ (a @ g), v @ (a @ f), v @ (a @ g)])

    def _free_body(self) -> int:
        drive = self.model.primitives[self.model.primitives[:, PRIM_KIND] == ANGLE]
        driven = {int(b) for b in drive[:, [PRIM_BODY_I, PRIM_BODY_J]].ravel()}
        return next(b for b in range(self.model.masses.size) if b not in driven)

    def observed_name(self) -> str:
        if self.model.joints.shape[0]:
            return (f"journal centre of {self.model.scene.clearance_joints[0].name} relative to "
                    "its bearing, across the bore")
        return f"centre of body {self.model.names[self._free_body()]}"


def poincare(flow, state, transient: int, periods: int, progress: bool = False):
    """Stroboscopic samples (periods x coordinates) after `transient` periods, and the states
    they were taken at (the last one: the state reached)."""
    if transient:
        state = flow.advance(state, transient)
    states = []
    for _ in tqdm(range(periods), desc="poincare", unit="period", disable=not progress):
        state = flow.advance(state)
        states.append(state)
    return np.array([flow.coordinates(s) for s in states]), states


def period_of(samples: np.ndarray, tol: float = 1e-4) -> int | None:
    """The smallest p <= MAX_PERIOD with x_(i+p) = x_i (to tol of the samples' scale) for
    every sample, or None."""
    scale = max(np.max(np.abs(samples)), 1e-300)
    for p in range(1, min(MAX_PERIOD, len(samples) // 2) + 1):
        if np.max(np.abs(samples[p:] - samples[:-p])) <= tol * scale:
            return p
    return None


def lyapunov(flow, state, periods: int, d0: float = 1e-7, seed: int = 0):
    """Largest Lyapunov exponent (1/s) by Benettin's renormalisation once per period, and its
    running estimate after each period (to show convergence). A neighbour whose separation
    collapses (every direction contracts onto the reference: a fully constrained mechanism)
    gives -inf."""
    rng = np.random.default_rng(seed)
    x0 = flow.coordinates(state)
    direction = rng.standard_normal(x0.size)
    neighbour = flow.perturb(state, d0 * direction / np.linalg.norm(direction))
    total, running = 0.0, []
    for k in range(periods):
        state, neighbour = flow.advance(state), flow.advance(neighbour)
        dx = flow.coordinates(neighbour) - flow.coordinates(state)
        d = np.linalg.norm(dx)
        if d < 1e-14 * d0:
            return -math.inf, running + [-math.inf]
        total += math.log(d / d0)
        running.append(total / ((k + 1) * flow.period))
        neighbour = flow.perturb(state, dx * (d0 / d))
    return running[-1], running


def classify(samples, exponent=None, tol=1e-4) -> tuple[str, int | None]:
    """("periodic", p), ("quasi-periodic", None) or ("chaotic", None)."""
    p = period_of(samples, tol)
    if p is not None:
        return "periodic", p
    if exponent is None:
        return "not periodic", None
    return ("chaotic" if exponent > 0 else "quasi-periodic"), None


def shooting(flow, state, multiple: int = 1, tol: float = 1e-9, iterations: int = 20, step: float = 1e-6):
    """A periodic orbit of period `multiple` driving periods from a guess `state`, by Newton
    on P^m(x) - x = 0 in the flow's coordinates. Returns (state on the orbit, Floquet
    multipliers, residual history). The Jacobian of P^m by forward differences of size `step`."""
    history = []
    for _ in range(iterations):
        x = flow.coordinates(state)
        end = flow.advance(state, multiple)
        residual = flow.coordinates(end) - x
        history.append(float(np.linalg.norm(residual)))
        jac = monodromy(flow, state, end, multiple, step)
        if history[-1] <= tol * max(np.linalg.norm(x), 1.0):
            return state, np.linalg.eigvals(jac), history
        dx = np.linalg.lstsq(jac - np.eye(x.size), -residual, rcond=None)[0]
        state = flow.perturb(state, dx)
    raise FloatingPointError(f"shooting did not converge in {iterations} Newton iterations "
                             f"(residuals {', '.join(f'{r:.2e}' for r in history)})")


def monodromy(flow, state, end, multiple, step):
    """d P^m / d x at `state` (forward differences; `end` = P^m(state))."""
    x_end = flow.coordinates(end)
    n = x_end.size
    jac = np.empty((n, n))
    for i in range(n):
        dx = np.zeros(n)
        dx[i] = step
        jac[:, i] = (flow.coordinates(flow.advance(flow.perturb(state, dx), multiple)) - x_end) / step
    return jac
