r"""Nonlinear dynamics of periodically driven systems, seen once per driving period.

A `Flow` is what the analyses need of a system: its driving period, a way to advance a state
by whole periods, the state's coordinates (normalised, so that distances mean something) and
a way to perturb a state along them. `MechanismFlow` wraps a driven mechanism of any kind
(reduced.mechanism: what only a body kind knows, its coordinates' scales and how a state is
put back on the constraints, is its back-end's `flow_*` functions); the tests wrap a forced
Duffing oscillator the same way, so every analysis is checked on a system with published
behaviour.

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
  by finite differences, continuation's at a fixed parameter (FixedFlow); its eigenvalues
  are the Floquet multipliers (stable when all lie inside the unit circle).
"""

import math
from dataclasses import dataclass, replace

import numpy as np
from tqdm import tqdm

from pinbore.reduced.dynamics.continuation import Continuation
from pinbore.reduced.mechanism import joints, kernel, outputs
from pinbore.reduced.mechanism.layout import (CONSTANT_SPEED, DISSIPATED, OK, PRIM_ANGLE0, PRIM_BODY_I, PRIM_BODY_J,
                                              PRIM_PROFILE, PRIM_SPEED, WORK_IN)
from pinbore.reduced.mechanism.model import Model
from pinbore.reduced.mechanism.run import STATUS, simulate

MAX_PERIOD = 16


@dataclass
class MechanismState:
    y: np.ndarray           # the engine's state vector
    speeds: np.ndarray      # impact speeds of the contacts
    mode: np.ndarray        # contact modes (held contacts of impulse joints)
    latched: np.ndarray     # latch flags of the torsion elements
    period: int             # periods elapsed since the start


class MechanismFlow:
    """A periodically forced mechanism (a drive at constant speed, a shaken drive, harmonic
    loads: the scene's forcing_period) advanced by whole periods. Coordinates: the body
    kind's positions and velocities (back-end `flow_coordinates`: a planar driven angle taken
    relative to the drive, spatial Euler parameters of one sign), scaled by the smallest
    clearance c and c omega, omega = 2 pi / period (back-end `flow_scale`). A drive turning
    at constant speed whose angle has no bound (the planar one) turns its angle0 on by 2 pi
    each period, as the integration restarts at t = 0 (where every load's phase repeats); a
    spatial drive holds its relative angle modulo 2 pi and needs no shift."""

    def __init__(self, model: Model):
        self.model = model
        self.back_end = model.kind.bodies()
        self.period = model.scene.forcing_period()
        self.omega = 2 * math.pi / self.period
        self.drive = None if model.drive_row is None else model.primitives[model.drive_row]
        self.turning = self.drive is not None and self.drive[PRIM_SPEED] != 0 and \
            int(self.drive[PRIM_PROFILE]) == CONSTANT_SPEED
        if self.turning:
            self.omega = math.copysign(self.omega, self.drive[PRIM_SPEED])
        self.length = min((c.gap() for c in model.joints), default=1e-3)
        self.scale = self.back_end.flow_scale(model, self.length, self.omega)
        self.last = None   # the Trajectory of the last advance (for the design study)

    def start(self) -> MechanismState:
        args = self.model.args()
        return MechanismState(self.model.y0.copy(), args.speeds, args.mode, args.latched, 0)

    def _primitives(self, period: int) -> np.ndarray:
        primitives = self.model.primitives
        if self.back_end.WRAPPED_ANGLES or not self.turning:
            return primitives
        primitives = primitives.copy()
        primitives[self.model.drive_row, PRIM_ANGLE0] += 2 * math.pi * period * math.copysign(1.0, self.omega)
        return primitives

    def advance(self, state: MechanismState, periods: int = 1) -> MechanismState:
        """The state `periods` drive periods on (the engine's impact speeds, modes and
        latches carried over); the trajectory is kept in self.last. An integration that stops
        is a FloatingPointError."""
        args = self.model.args(state.speeds, state.latched, state.mode, self._primitives(state.period))
        self.last = simulate(self.model, state.y, periods * self.period, args)
        if self.last.status != OK:
            raise FloatingPointError(f"the integration stopped at t = {self.last.t_end:.6g} s "
                                     f"of period {state.period}: {STATUS[self.last.status]}")
        return MechanismState(self.last.states[-1].copy(), args.speeds, args.mode, args.latched,
                              state.period + periods)

    def coordinates(self, state: MechanismState) -> np.ndarray:
        return self.back_end.flow_coordinates(self.model, state.y, self._primitives(state.period)) / self.scale

    def perturb(self, state: MechanismState, dx: np.ndarray) -> MechanismState:
        """The state moved by dx (in coordinates), then made consistent with the ideal joints
        and the drive."""
        nq = self.model.nq
        y = state.y.copy()
        y[:2 * nq] += dx * self.scale * self.back_end.flow_signs(self.model, y)
        args = self.model.args(state.speeds, state.latched, primitives=self._primitives(state.period))
        return replace(state, y=self.back_end.flow_consistent(self.model, y, args))

    def _observed_joint(self):
        """The first clearance joint's bodies, points and the two vectors of the bearing body
        (its frame) the observed point is measured along (its type's `across`: a guide's axis
        and face normal, a journal's two directions across its bore's axis, otherwise the
        frame's x and y)."""
        c, model = self.model.joints[0], self.model
        index = model.geometry.index
        f, g = joints.of(c).across()
        return (index[c.bearing_body], tuple(map(float, c.bearing_point)), index[c.journal_body],
                tuple(map(float, c.journal_point)), tuple(map(float, f)), tuple(map(float, g)))

    def _free_body(self) -> int:
        driven = set() if self.drive is None else {int(self.drive[PRIM_BODY_I]), int(self.drive[PRIM_BODY_J])}
        return next(b for b in range(len(self.model.names)) if b not in driven)

    def observed(self, state: MechanismState) -> np.ndarray:
        """What the Poincare map shows: the first clearance joint's journal (slider) centre
        relative to its bearing (guide) point (m) and its rate (m/s), along the bearing
        body's two directions across the joint; without clearance joints, the centre of the
        first body that is not driven (x, y global)."""
        args = self.model.args()
        return self._observed_at(state.y, args, kernel.workspace(args), self._observed_where())

    def _observed_where(self):
        """What the observed point is measured from: the first clearance joint's bodies,
        points and vectors (_observed_joint), or the coordinate of the first body that is not
        driven."""
        model = self.model
        return self._observed_joint() if model.joints else model.geometry.coordinate(self._free_body())

    def _observed_at(self, y, args, work, where) -> np.ndarray:
        """The observed point's two positions (m) and their rates (m/s) at the state y."""
        if not self.model.joints:
            nq = self.model.nq
            return np.array([*y[where:where + 2], *y[nq + where:nq + where + 2]])
        return np.array(kernel.relative_motion(y, args, work, *where))

    def orbit_measures(self) -> dict:
        """What the last advance shows of its orbit, seen as the time-domain outputs see a run
        (reduced.mechanism.outputs: each step with the law memory it was taken with, its
        extremes refined between the steps on the cubic Hermite interpolant of the state):
        `amplitude`, half the peak-to-peak range of the observed point's positions (m; the
        larger of its two directions), `amplitudes` of each, `gap`, the smallest distance to
        contact over the orbit (m; minus the deepest penetration when it touches), and
        `peak_force`, the first clearance joint's largest normal force (N, as summary.json's
        peak_normal_force_N; both None without clearance joints); `dissipated` and `work_in`,
        the energy dissipated and the work of the drive and loads over the orbit (J: equal
        on a periodic orbit, where every stored energy returns)."""
        model, run = self.model, self.last
        where = self._observed_where()
        seen = outputs.observed_steps(model, run)
        positions = np.array([self._observed_at(y, seen["args"], seen["work"], where)[:2] for y in run.states])

        def extreme(i, sign):   # the largest of sign x position i, refined
            along = lambda t, y, args, work: sign * self._observed_at(y, args, work, where)[i]   # noqa: E731
            return outputs.refined_max(model, run, int(np.argmax(sign * positions[:, i])), along)[0]
        amplitudes = [0.5 * (extreme(i, 1.0) + extreme(i, -1.0)) for i in range(positions.shape[1])]
        book = run.states[:, 2 * model.nq + DISSIPATED: 2 * model.nq + WORK_IN + 1]
        measures = {"amplitude": float(max(amplitudes)), "amplitudes": amplitudes, "gap": None,
                    "peak_force": None, "dissipated": float(book[-1, 0] - book[0, 0]),
                    "work_in": float(book[-1, 1] - book[0, 1])}
        nc = model.contacts.shape[0]
        if nc:
            dy, depth, offset = np.empty(run.states.shape[1]), np.empty(nc), np.zeros((nc, model.kind.dimension))

            def deepest(t, y, args, work):
                kernel.observe(t, y, dy, args, work, depth, offset)
                return depth.max()
            k = int(np.argmax(seen["depths"].max(axis=1)))
            measures["gap"] = -outputs.refined_max(model, run, k, deepest)[0]
            force = outputs.joint_force(outputs.roles(model, 0), seen["normals"])
            measures["peak_force"] = outputs.joint_peak(model, 0, run, force)[0]
        return measures

    def observed_name(self) -> str:
        if self.model.joints:
            return (f"journal centre of {self.model.joints[0].name} relative to its bearing, "
                    "across the joint")
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


AGREEMENT_GROWTH = 0.1   # e-folds per drive period: a periodic attractor's exponent stays below


def disagreement(kind: str, exponent, period_s: float) -> str | None:
    """Why the class of the samples and the largest Lyapunov exponent contradict each other,
    or None. Samples that repeat belong to a periodic attractor, whose largest exponent is
    negative (a driven mechanism's map has no neutral direction along the flow); an estimate
    growing by more than AGREEMENT_GROWTH e-folds a period says otherwise (a chaotic motion
    of small amplitude, or a finite-time estimate upset by the impacts' timing). Chaos with a
    negative exponent cannot be: classify never says so."""
    if kind == "periodic" and exponent is not None and exponent * period_s > AGREEMENT_GROWTH:
        return (f"the samples repeat, but the largest Lyapunov exponent is {exponent:+.4g} 1/s "
                f"({exponent * period_s:+.3g} e-folds per drive period): the motion may be "
                "chaotic at an amplitude below the samples' tolerance, or the estimate is "
                "upset by the impacts; run --analysis lyapunov with more periods")
    return None


def classify(samples, exponent=None, tol=1e-4) -> tuple[str, int | None]:
    """("periodic", p), ("quasi-periodic", None) or ("chaotic", None)."""
    p = period_of(samples, tol)
    if p is not None:
        return "periodic", p
    if exponent is None:
        return "not periodic", None
    return ("chaotic" if exponent > 0 else "quasi-periodic"), None


class FixedFlow:
    """A flow at its own parameter as a family of continuation (reduced.dynamics.continuation):
    x its coordinates, the state at x the template moved there (flow.perturb: onto the ideal
    joints and the drive), the parameter unused."""

    def __init__(self, flow, template, tolerance: float):
        self.flow, self.template, self.tolerance = flow, template, tolerance
        self.origin = flow.coordinates(template)

    def state(self, x):
        return self.flow.perturb(self.template, x - self.origin)

    def map(self, x, p, multiple):
        return self.flow.coordinates(self.flow.advance(self.state(x), multiple))

    def consistent(self, x, p):
        return self.flow.coordinates(self.state(x))

    def measure(self, x, p, multiple) -> dict:
        return {}


def shooting(flow, state, multiple: int = 1, tol: float = 1e-9, iterations: int = 20):
    """A periodic orbit of period `multiple` driving periods from a guess `state`, by Newton
    on P^m(x) - x = 0 in the flow's coordinates: continuation's Newton at a fixed parameter
    (Continuation.first; its monodromy by central differences at the step continuation
    argues, along the joints' tangent space), until |P^m(x) - x| <= tol (1 + |x|), tol at
    least continuation's NEWTON_TOL. Returns (state on the orbit, Floquet multipliers,
    residual history, spread: how far the largest multiplier's modulus moves when the
    difference step doubles at the step Continuation.resolve chooses; None when not measured)."""
    family = FixedFlow(flow, state, tol)
    line = Continuation(family, 0.0, 1.0, multiple)
    try:
        orbit = line.first(family.origin, 0.5, 1.0, iterations)
    except FloatingPointError as err:
        residuals = ", ".join(f"{r:.2e}" for r in line.residuals)
        if len(line.residuals) <= iterations:   # an integration stopped (not every residual taken)
            raise FloatingPointError(f"shooting stopped after the residuals {residuals}: {err}") from None
        raise FloatingPointError(f"shooting did not converge in {iterations} Newton iterations "
                                 f"(residuals {residuals})") from None
    orbit, spread = line.resolve(orbit)
    return family.state(orbit.x), orbit.multipliers, line.residuals, spread
