"""`pinbore dynamics SCENE --analysis ... --out DIR`: Poincare maps, bifurcation diagrams,
Lyapunov exponents, periodic orbits by shooting and design studies of a driven mechanism.

`ANALYSES` maps each analysis to its options model (`pinbore.reduced.dynamics.analyses`, validated
before any work) and the function that runs it; `run` checks the scene against the options,
runs the analysis into a temporary folder and moves it into place when complete.

A sweep's parameter is a dotted key of the scene or a shorthand for some
(pinbore.reduced.dynamics.parameters); each of its points is the scene's data with it set.
The points run through the sweep engine of `pinbore study` (core.sweep): in parallel on the
local cores, or on a Dask cluster when `--scheduler ADDRESS` is given, each cached by its
content as soon as it is done, so an interrupted sweep resumes where it stopped and a point
another sweep ran on the same scene is read, not run again. What is particular to dynamics
stays here: the point of a bifurcation diagram and of a design map, their tables, and the
mechanisms a continuation follows.
"""

import dataclasses
import json
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pinbore.core import scene as scenes
from pinbore.core import sweep
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.core.codedeps import code_hash
from pinbore.reduced.dynamics.analyses import (Analysis, BifurcationOptions, ContinuationOptions, DesignOptions,
                                               LyapunovOptions, PoincareOptions, Sampled, ShootingOptions, Sweep)
from pinbore.reduced.dynamics.parameters import label, parameter_value, with_parameter
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.layout import PRIM_ANGLE0


def scene_model(data: dict) -> type:
    """The scene model of a mechanism scene's data of any kind (reduced.mechanism.kinds)."""
    return kinds.kind_of(data, "scene").scene


def continuation():
    """Pseudo-arclength continuation (reduced.dynamics.continuation)."""
    from pinbore.reduced.dynamics import continuation as method   # noqa: PLC0415

    return method


def figures():
    """The analyses' tables and figures (reduced.dynamics.plots; importing it loads
    matplotlib, which refusing a bad scene does not need)."""
    from pinbore.reduced.dynamics import plots   # noqa: PLC0415

    return plots


def dynamics():
    """The flow and its analyses (reduced.dynamics.flow; imported only once a scene has been
    validated)."""
    from pinbore.reduced.dynamics import flow   # noqa: PLC0415

    return flow


def require_forcing(scene, source: str) -> float:
    """The period of the scene's forcing (s): the Poincare section is taken once a period
    (MechanismScene.forcing_period; one InputError line when the forcing is not periodic)."""
    try:
        return scene.forcing_period()
    except ValueError as err:
        raise InputError(f"{source}: {err}") from None


def mechanism_flow(data: dict, base: Path, source: str, ideal: bool = False):
    """The flow (reduced.dynamics.flow.MechanismFlow) of a driven scene's data (`ideal`: of
    its ideal twin, every clearance joint closed)."""
    from pinbore.reduced.mechanism.model import build   # noqa: PLC0415 (compiled)

    scene = scene_model(data).model_validate(data)
    require_forcing(scene, source)
    return dynamics().MechanismFlow(build(scene, source, base, ideal=ideal))


@dataclass(frozen=True)
class SceneFile:
    """The scene an analysis runs on: its file and its validated data (sweeps set their
    parameter in copies of it)."""

    path: Path
    data: dict

    @property
    def source(self) -> str:
        return str(self.path)

    @property
    def base(self) -> Path:
        """The folder that relative paths in the scene (laws_file) start from."""
        return self.path.parent

    def flow(self):
        return mechanism_flow(self.data, self.base, self.source)


def observed_samples(flow, states) -> np.ndarray:
    """The observed point (x, y in m, and its velocity in m/s) at each state."""
    return np.array([flow.observed(s) for s in states])


class BifurcationPoint:
    """One point of a sweep, run on its scene's data: Poincare samples of the observed point
    and the classification (periodic with its period, quasi-periodic, chaotic); the largest
    Lyapunov exponent only where the samples are not periodic, over a fifth of the sampled
    periods (at least 10: enough for its sign; `--analysis lyapunov` gives the converged
    value)."""

    def __init__(self, base, source, transient, periods):
        self.base, self.source = base, source
        self.transient, self.periods = transient, periods

    def __call__(self, data: dict) -> dict:
        try:
            return self._point(data)
        except FloatingPointError as err:   # a point whose integration fails is marked, not lost
            return {"kind": "failed", "period": None, "lyapunov_per_s": None, "observed": [],
                    "reason": str(err)}

    def _point(self, data: dict) -> dict:
        flow = mechanism_flow(data, self.base, self.source)
        coords, states = dynamics().poincare(flow, flow.start(), self.transient, self.periods)
        exponent = None
        if dynamics().period_of(coords) is None:
            exponent, _ = dynamics().lyapunov(flow, states[-1], max(self.periods // 5, 10))
        kind, period = dynamics().classify(coords, exponent)
        return {"kind": kind, "period": period,
                "lyapunov_per_s": exponent if exponent is None or math.isfinite(exponent) else None,
                "observed": observed_samples(flow, states).tolist()}


def swept(target: SceneFile, analysis: str, task, points: list[dict], options: Sweep) -> list[dict]:
    """task(data) of every point's scene data, through the sweep engine (core.sweep.run: on the
    options' workers or cluster), each result cached by the point's content: the analysis, its
    whole scene, the files it names, the code that runs it (this module's import closure,
    core.codedeps: the compiled core's binary included) and the periods it discards and samples.
    A point cached by another sweep of one scene (another range, the parameter by another name)
    is read, not run again."""
    files = sweep.digest_files(sweep.named_files(points, target.base))
    keys = sweep.point_keys(f"dynamics.{analysis}", points, files, code_hash(__name__),
                            options.transient, options.periods)
    return sweep.run(task, points, keys, options)[0]


class DesignPoint:
    """Peak contact force, impacts per revolution and the RMS deviation of the slider's
    acceleration from the ideal joint's (as a fraction of the ideal's RMS), over the sampled
    revolutions after the transient, of one point's scene data (a clearance, a speed)."""

    def __init__(self, base, source, transient, periods):
        self.base, self.source = base, source
        self.transient, self.periods = transient, periods

    def __call__(self, data: dict) -> dict:
        try:
            return self._point(data)
        except FloatingPointError as err:   # marked (NaN: blank in the map, outside every band)
            return {"peak_force_N": math.nan, "impacts_per_revolution": math.nan,
                    "acceleration_deviation": math.nan, "reason": str(err)}

    def _point(self, data: dict) -> dict:
        flow = mechanism_flow(data, self.base, self.source)
        state = flow.advance(flow.start(), self.transient)
        flow.advance(state, self.periods)
        cols = per_step_of(flow)
        ideal = mechanism_flow(data, self.base, self.source, ideal=True)
        ideal.advance(ideal.start(), 1)
        ideal_cols = per_step_of(ideal)
        angle, acceleration = slider_motion(flow, cols)
        ideal_angle, ideal_acceleration = slider_motion(ideal, ideal_cols)
        order = np.argsort(ideal_angle)
        reference = np.interp(angle, ideal_angle[order], ideal_acceleration[order],
                              period=2 * math.pi)
        deviation = math.sqrt(np.mean((acceleration - reference) ** 2)
                              / np.mean(ideal_acceleration ** 2))
        forces = [cols[f"{c.name}_normal_force_N"] for c in flow.model.joints]
        return {"peak_force_N": float(max(np.max(f) for f in forces)),
                "impacts_per_revolution": float(flow.last.counters[3]) / self.periods,
                "acceleration_deviation": deviation}


def per_step_of(flow) -> dict:
    """The columns of the flow's last advance (reduced.mechanism.outputs)."""
    from pinbore.reduced.mechanism import outputs   # noqa: PLC0415 (compiled)

    return outputs.per_step(flow.model, flow.last)[0]


def slider_motion(flow, cols) -> tuple[np.ndarray, np.ndarray]:
    """At each step of the flow's last advance: the drive's phase angle0 + omega t in
    [0, 2 pi) (t restarting at 0 on a whole period) and the slider's acceleration along its
    guide (the body kind's slider_acceleration)."""
    phase = flow.drive[PRIM_ANGLE0] + flow.omega * cols["time_s"]
    return np.mod(phase, 2 * math.pi), flow.back_end.slider_acceleration(flow.model, cols)


def design_band(rows, speeds, max_force, max_deviation) -> dict:
    """Per speed, the clearances (m) whose peak force and acceleration deviation stay within
    the thresholds."""
    band = {}
    for speed in speeds:
        ok = [r["clearance_m"] for r in rows if r["speed_rpm"] == speed
              and r["peak_force_N"] <= max_force and r["acceleration_deviation"] <= max_deviation]
        band[f"{speed:g}"] = {"clearances_m": ok, "low_m": min(ok, default=None), "high_m": max(ok, default=None)}
    return band


def run(scene_file: str | Path, analysis: str, options: Analysis) -> int:
    """The `pinbore dynamics` command: `analysis` (a key of ANALYSES) with its validated
    options; outputs in options.out (replaced when complete). 1 if shooting did not
    converge (its outputs are written, marked)."""
    path = Path(scene_file)
    scene = kinds.load(path)   # validates, one-line errors
    target = SceneFile(path, scene.model_dump(exclude_none=True))
    check_scene(scene, target, options)
    _, analyse = ANALYSES[analysis]
    start = time.perf_counter()
    summary = {"scene_file": target.source, "analysis": analysis, "transient_periods": options.transient}
    if isinstance(options, Sampled):
        summary["periods"] = options.periods
    try:
        with atomic_directory(options.out) as tmp:
            summary |= analyse(target, options, tmp)
            summary["wall_time_s"] = time.perf_counter() - start
            (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    except FloatingPointError as err:
        print(f"pinbore dynamics: {target.source}: {err}; nothing written", file=sys.stderr)
        return 1
    if summary.get("converged", True):
        return 0
    print(f"pinbore dynamics: {target.source}: {summary['reason']}; wrote {options.out}/summary.json "
          "(converged: false)", file=sys.stderr)
    return 1


def check_scene(scene, target: SceneFile, options: Analysis) -> None:
    """What the options need of the scene, before any work: a drive (the section is taken
    once per revolution); the keys of every swept parameter, and a valid scene with a
    periodic forcing at both ends of its range (e.g. a clearance below the bearing's radius,
    a friction law with a coefficient mu to set, a speed other than 0); a prismatic body for
    the design study to measure."""
    require_forcing(scene, target.source)
    if isinstance(options, DesignOptions) and (scene.drive is None or scene.drive.speed_rpm is None):
        raise InputError(f"{target.source}: drive: the design study sweeps the drive's speed; "
                         "the scene has no drive turning at constant speed")
    for option, parameter, span in options.swept():
        for value in (span.low, span.high):
            where = f"--{option}: {target.source} with {parameter} {value:g}"
            require_forcing(scenes.validate(type(scene), with_parameter(target.data, parameter, value,
                                                                        target.source), where), where)
    if isinstance(options, ContinuationOptions):
        value = parameter_value(scene, target.data, options.parameter)
        if not options.range.low <= value <= options.range.high:
            raise InputError(f"--range: the branch starts at the scene's {options.parameter} "
                             f"{value:g}, outside {options.range.low:g} {options.range.high:g}")
    if isinstance(options, DesignOptions) and not any(j.guides_a_slider for j in scene.joints):
        raise InputError(f"{target.source}: joints: the design study measures a prismatic body's "
                         "acceleration; the scene has no prismatic joint")


def poincare_map(target: SceneFile, options: PoincareOptions, tmp: Path) -> dict:
    """The Poincare samples after the transient, their class and the largest exponent."""
    flow = target.flow()
    coords, states = dynamics().poincare(flow, flow.start(), options.transient, options.periods,
                                       progress=True)
    exponent, _ = dynamics().lyapunov(flow, states[-1], options.periods)
    kind, period = dynamics().classify(coords, exponent)
    doubt = dynamics().disagreement(kind, exponent, flow.period)
    if doubt:
        print(f"pinbore dynamics: {target.source}: warning: {doubt}", file=sys.stderr)
    samples = observed_samples(flow, states)
    figures().write_table(tmp / "poincare.csv", ["period", "x_m", "y_m", "vx_m_per_s", "vy_m_per_s"],
                      [[options.transient + k + 1, *row] for k, row in enumerate(samples)])
    figures().poincare(tmp / "poincare.png", samples, flow.length, f"{target.path.stem}: {kind}"
                   + (f", period {period}" if period else ""), flow.observed_name())
    return {"observed": flow.observed_name(), "kind": kind, "period": period,
            "lyapunov_per_s": _finite(exponent), "disagreement": doubt}


def lyapunov_exponent(target: SceneFile, options: LyapunovOptions, tmp: Path) -> dict:
    """The largest Lyapunov exponent after the transient, and its running estimate."""
    flow = target.flow()
    state = flow.advance(flow.start(), options.transient)
    exponent, running = dynamics().lyapunov(flow, state, options.periods)
    figures().write_table(tmp / "lyapunov.csv", ["period", "running_estimate_per_s"],
                      [[k + 1, v] for k, v in enumerate(running)])
    figures().convergence(tmp / "lyapunov.png", running)
    tail = [v for v in running[len(running) * 3 // 4:] if math.isfinite(v)]
    return {"lyapunov_per_s": _finite(exponent),
            "last_quarter_spread_per_s": (max(tail) - min(tail)) if tail else None}


def periodic_orbit(target: SceneFile, options: ShootingOptions, tmp: Path) -> dict:
    """The periodic orbit by shooting from the state after the transient, with its Floquet
    multipliers; `converged: false` and the reason when Newton fails."""
    flow = target.flow()
    state = flow.advance(flow.start(), options.transient)
    try:
        orbit, multipliers, history, spread = dynamics().shooting(flow, state, options.multiple)
    except FloatingPointError as err:
        return {"converged": False, "reason": str(err)}
    warning = spread_warning(target, spread, "the scene's own value")
    warnings = [warning] if warning else []
    return {"converged": True, "residuals": history,
            "floquet_multipliers": [[m.real, m.imag] for m in multipliers],
            "largest_multiplier_modulus": float(np.max(np.abs(multipliers))),
            "multiplier_spread": spread,
            "stable": bool(np.max(np.abs(multipliers)) < 1),
            "observed": flow.observed(orbit).tolist(), "warnings": warnings}


def spread_warning(target: SceneFile, spread: float | None, where: str) -> str | None:
    """The warning, printed, of a monodromy that does not resolve the stability
    (the spread of Continuation.resolve above SPREAD_WARNING at every step it tries, or not
    measured); None when it does."""
    if spread is not None and spread <= continuation().SPREAD_WARNING:
        return None
    if spread is None:
        warning = (f"{target.source}: what the monodromy resolves of the stability at {where} is not "
                   f"measured (an orbit perturbed by twice the difference step did not integrate)")
    else:
        warning = (f"{target.source}: the largest Floquet multiplier at {where} moves by {spread:.2g} "
                   f"when the monodromy's difference step doubles, at the least of the steps tried "
                   f"(the map is not smooth at their scale): stability and bifurcations within {spread:.2g} of "
                   f"|mu| = 1 are not resolved")
    print(f"pinbore dynamics: warning: {warning}", file=sys.stderr)
    return warning


BIFURCATION_COLUMNS = ["value", "kind", "period", "lyapunov_per_s", "x_m", "y_m"]   # bifurcation.csv


def bifurcation_diagram(target: SceneFile, options: BifurcationOptions, tmp: Path) -> dict:
    """The swept parameter's points, each classified from its Poincare samples."""
    values = np.linspace(options.range.low, options.range.high, options.points).tolist()
    points = [with_parameter(target.data, options.parameter, v, target.source) for v in values]
    task = BifurcationPoint(target.base, target.source, options.transient, options.periods)
    rows = [{"value": v} | r for v, r in zip(values, swept(target, "bifurcation", task, points, options))]
    figures().write_table(tmp / "bifurcation.csv", BIFURCATION_COLUMNS,
                      [[r["value"], r["kind"], r["period"], r["lyapunov_per_s"], *j[:2]]
                       for r in rows for j in (r["observed"] or [[None, None]])])   # a failed point: one row
    figures().bifurcation(tmp / "bifurcation.png", rows, options.parameter, label(options.parameter))
    kinds = [r["kind"] for r in rows]
    return {"parameter": options.parameter, "range": list(options.range), "points": options.points,
            "counts": {k: kinds.count(k) for k in sorted(set(kinds))}}


def design_map(target: SceneFile, options: DesignOptions, tmp: Path) -> dict:
    """The design study on the clearance x speed grid, and per speed the clearance band
    within the thresholds."""
    clearances = np.linspace(options.range.low, options.range.high, options.points).tolist()
    speeds = np.linspace(options.speeds.low, options.speeds.high, options.speeds.count).tolist()
    grid = [(c, v) for v in speeds for c in clearances]
    points = [with_parameter(with_parameter(target.data, "speed", v, target.source), "clearance", c,
                             target.source) for c, v in grid]
    task = DesignPoint(target.base, target.source, options.transient, options.periods)
    rows = [{"clearance_m": c, "speed_rpm": v} | r
            for (c, v), r in zip(grid, swept(target, "design", task, points, options))]
    names = ["clearance_m", "speed_rpm", "peak_force_N", "impacts_per_revolution",
             "acceleration_deviation"]
    figures().write_table(tmp / "design.csv", names, [[r[n] for n in names] for r in rows])
    figures().design(tmp / "design.png", rows, clearances, speeds, options.max_force, options.max_deviation)
    return {"thresholds": {"peak_force_N": options.max_force,
                           "acceleration_deviation": options.max_deviation},
            "band": design_band(rows, speeds, options.max_force, options.max_deviation)}


class MechanismFamily:
    """A scene's mechanisms over one parameter, as continuation needs them
    (reduced.dynamics.continuation): the map of the scaled coordinates x over `multiple`
    forcing periods at p, and the orbit's measures. x is scaled by the clearance c of the
    flow at the scene's own value, its velocities by c omega(p), omega of the flow at p: a
    forcing frequency or a drive's speed scales every velocity of the motion, and at one
    fixed velocity scale the pseudo-arclength measured that growth rather than the
    parameter's change (measured: the Flores slider-crank with friction, 40 points from
    100 rpm covered 0.52 rpm, at c omega(p) 18 rpm); a state at p is
    the template state (the last orbit's end: its impact speeds, contact modes, latches,
    friction states and the periods elapsed, which a turning drive's angle counts) moved to
    x and onto the constraints. The models of the last few p are
    kept (a model is rebuilt at a new p)."""

    KEPT = 4

    def __init__(self, target: "SceneFile", parameter: str, value: float):
        self.target, self.parameter = target, parameter
        self.flows = {}
        reference = self.flow(value)
        integrator = reference.model.scene.integrator
        self.tolerance = 100 * integrator.rtol   # what a converged orbit resolves
        self.scale, self.omega = reference.scale.copy(), reference.omega
        self.template = reference.start()
        # what the integration resolves of x: its error control allows rtol |y_i| + atol in
        # each coordinate, in scaled units rtol |x_i| + atol / scale_i (a body far from the
        # origin, in clearances, is resolved coarsely however small its motion)
        x = np.abs(self.coordinates(reference, self.template))
        self.extent = float(np.max(x))
        self.resolution = float(np.max(integrator.rtol * x + integrator.atol / self.scale))

    def flow(self, p: float):
        if p not in self.flows:
            if len(self.flows) >= self.KEPT:
                self.flows.pop(next(iter(self.flows)))
            data = with_parameter(self.target.data, self.parameter, p, self.target.source)
            self.flows[p] = mechanism_flow(data, self.target.base, self.target.source)
        return self.flows[p]

    def scale_at(self, flow) -> np.ndarray:
        """The scale of x at the flow's parameter: c, and c omega(p) for the velocities (the
        second half of the coordinates)."""
        scale = self.scale.copy()
        scale[scale.size // 2:] *= flow.omega / self.omega
        return scale

    def coordinates(self, flow, state) -> np.ndarray:
        return flow.coordinates(state) * flow.scale / self.scale_at(flow)

    def state(self, flow, x):
        return flow.perturb(self.template,
                            x * self.scale_at(flow) / flow.scale - flow.coordinates(self.template))

    def map(self, x, p, multiple):
        flow = self.flow(p)
        return self.coordinates(flow, flow.advance(self.state(flow, x), multiple))

    def consistent(self, x, p):
        """x moved onto the ideal joints and the drive, as `map` moves it before it integrates
        (continuation differences the monodromy along their tangent space only)."""
        flow = self.flow(p)
        return self.coordinates(flow, self.state(flow, x))

    def measure(self, x, p, multiple) -> dict:
        """The orbit's measures (flow.orbit_measures); its end becomes the template."""
        flow = self.flow(p)
        self.template = flow.advance(self.state(flow, x), multiple)
        return flow.orbit_measures()

    def settle(self, p, periods, state=None):
        """The state `periods` forcing periods on at p from `state` (default: the template),
        its coordinates, and the measures of its last period (a direct sweep's value)."""
        flow = self.flow(p)
        if state is None:
            state = self.template
        state = flow.advance(state, periods)
        return state, self.coordinates(flow, state), flow.orbit_measures()


def resolution_warning(family: MechanismFamily, scene, source: str) -> str | None:
    """A warning when the integration's error control allows more in a scaled coordinate
    than the monodromy's difference step (MechanismFamily.resolution > FD_STEP): a body many
    clearances from the origin is resolved coarsely however small its motion, and the
    differences then carry the integration's error as noise (the shaken panel, 1e4
    clearances out: at rtol 1e-7 quotients at steps h and 2h differ by 5 %, at 1e-9 by 2 %,
    their truncation; spurious folds and doublings cluster where the noise turns the
    multipliers). None otherwise."""
    step = continuation().FD_STEP
    if family.resolution <= step:
        return None
    rtol = scene.integrator.rtol
    return (f"{source}: integrator.rtol: its error control allows {family.resolution:.2g} of a "
            f"clearance in a coordinate (here up to {family.extent:.3g} clearances from the origin), "
            f"more than the monodromy's difference step {step:g}: its multipliers and bifurcations may "
            f"be noise; integrator.rtol <= {rtol * step / family.resolution:.1g} resolves it")


def continued(target: SceneFile, options: ContinuationOptions, tmp: Path) -> dict:
    """The branch of periodic orbits across the range, both ways from the scene's value, its
    bifurcations, the doubled branch of each period doubling (switched onto there), and the
    direct up- and down-sweeps; `converged: false` and the reason when a branch could not be
    followed across the whole range (what converged is written)."""
    scene = scene_model(target.data).model_validate(target.data)
    start_value = parameter_value(scene, target.data, options.parameter)
    low, high = options.range
    family = MechanismFamily(target, options.parameter, start_value)
    method = continuation()
    warning = resolution_warning(family, scene, target.source)
    warnings = [warning] if warning else []
    if warning:
        print(f"pinbore dynamics: warning: {warning}", file=sys.stderr)
    line = method.Continuation(family, low, high, options.multiple)
    ds = (options.step if options.step is not None else (high - low) / 100) / (high - low)
    started = time.perf_counter()
    state, x, _ = family.settle(start_value, options.transient)
    family.template = state   # the contact modes, impact speeds and friction states of x
    try:
        first = line.first(x, start_value, 1.0)
    except FloatingPointError as err:
        reason = (f"no periodic orbit found from the state after {options.transient} transient "
                  f"periods at {options.parameter} {start_value:g} ({err}); the motion there may "
                  f"not be periodic (--analysis poincare shows it)")
        return {"converged": False, "reason": reason, "parameter": options.parameter, "warnings": warnings}
    first, spread = line.resolve(first)
    warning = spread_warning(target, spread, f"{options.parameter} {start_value:g}")
    if warning:
        warnings.append(warning)
    branches = []
    template = family.template   # the first orbit's: each way starts from it, not from where the other ended
    for direction in (-1.0, 1.0):
        if (direction < 0 and start_value <= low) or (direction > 0 and start_value >= high):
            continue
        family.template = template
        way = dataclasses.replace(first, tangent=direction * first.tangent)
        branches.append(line.run(way, ds, max(options.points // 2, 2), progress=True))
    specials = [s for b in branches for s in b.specials]
    doubled = [line.doubled(s, ds, max(options.points // 4, 2), progress=True)
               for s in specials if s.kind == "period_doubling"]
    doubled = [b for b in doubled if b is not None]
    points = [p for b in branches + doubled for p in b.points]
    cost = (time.perf_counter() - started) / max(len(points), 1)
    down = branches[0] if len(branches) == 2 else None
    rows = [point_row(0, options.multiple, p) for p in reversed(down.points)] if down else []
    rows += [point_row(0, options.multiple, p) for p in branches[-1].points[(1 if down else 0):]]
    for k, b in enumerate(doubled, start=1):   # each period doubling's doubled branch
        rows += [point_row(k, b.multiple, p) for p in b.points]
        specials += b.specials
    figures().write_table(tmp / "continuation.csv", CONTINUATION_COLUMNS, rows)
    figures().write_table(tmp / "bifurcations.csv", SPECIAL_COLUMNS, [special_row(s) for s in specials])
    sweeps = direct_sweeps(family, options) if options.sweeps else []
    if sweeps:
        figures().write_table(tmp / "sweeps.csv", SWEEP_COLUMNS, sweeps)
    figures().response(tmp / "response.png", rows, specials, sweeps, options.parameter,
                       label(options.parameter), f"{target.path.stem}: {family.flow(start_value).observed_name()}")
    reasons = [b.reason for b in branches + doubled if not b.complete]
    reasons += [f"the branch stopped at its {len(b.points)} points at {b.points[-1].p:.6g}, short of "
                f"the range [{low:g}, {high:g}] (more --points, or a larger --step)"
                for b in branches if b.complete and low < b.points[-1].p < high]
    return {"parameter": options.parameter, "range": [low, high], "start": start_value,
            "multiple": options.multiple, "points": len(rows), "seconds_per_point": cost,
            "converged": not reasons, "reason": "; ".join(reasons),
            "doubled_branches": len(doubled),
            "bifurcations": [{"kind": s.kind, "value": s.p, "amplitude_m": s.point.measures["amplitude"],
                              "floquet_multipliers": [[m.real, m.imag] for m in s.point.multipliers]}
                             for s in specials],
            "stable_points": sum(r[4] for r in rows),
            "start_floquet_multipliers": [[m.real, m.imag] for m in first.multipliers],
            "start_stable": first.stable, "start_multiplier_spread": spread,
            "difference_step": line.step, "warnings": warnings}


CONTINUATION_COLUMNS = ["branch", "multiple", "value", "amplitude_m", "stable", "largest_multiplier_modulus",
                        "gap_m", "peak_force_N", "dissipated_J", "x"]
SPECIAL_COLUMNS = ["kind", "value", "amplitude_m", "gap_m", "multipliers"]
SWEEP_COLUMNS = ["direction", "value", "amplitude_m", "gap_m", "peak_force_N"]


def point_row(branch: int, multiple: int, p) -> list:
    """A row of continuation.csv: the branch (0 the continued one, k the doubled branch of
    the k-th period doubling), its period in forcing periods, the orbit and its measures
    (flow.MechanismFlow.orbit_measures; dissipated_J: the energy it dissipates in a period)."""
    return [branch, multiple, p.p, p.measures["amplitude"], int(p.stable),
            p.largest, p.measures["gap"], p.measures.get("peak_force"), p.measures.get("dissipated"),
            " ".join(f"{v:.9g}" for v in p.x)]


def special_row(s) -> list:
    return [s.kind, s.p, s.point.measures["amplitude"], s.point.measures["gap"],
            " ".join(f"{m.real:.6g}{m.imag:+.6g}j" for m in s.point.multipliers)]


def direct_sweeps(family: MechanismFamily, options: ContinuationOptions) -> list:
    """Up- and down-sweep by direct integration, as on a shaker: each starts from the scene's
    initial state at its first value; at each value the state the last value reached runs
    `transient` periods, then the largest amplitude, the smallest gap and the largest normal
    force of `periods` periods are kept."""
    values = np.linspace(options.range.low, options.range.high, options.sweeps)
    rows = []
    for direction, order in (("up", values), ("down", values[::-1])):
        state = family.flow(float(order[0])).start()
        for value in tqdm(order, desc=f"{direction}-sweep", unit="value"):
            try:
                state, _, _ = family.settle(float(value), options.transient, state)
                amplitude, gap, force = 0.0, None, None
                for _ in range(options.periods):
                    state, _, measures = family.settle(float(value), 1, state)
                    amplitude = max(amplitude, measures["amplitude"])
                    if measures["gap"] is not None:
                        gap = measures["gap"] if gap is None else min(gap, measures["gap"])
                    if measures["peak_force"] is not None:
                        force = max(force or 0.0, measures["peak_force"])
            except FloatingPointError:
                rows.append([direction, float(value), math.nan, math.nan, math.nan])
                state = family.flow(float(value)).start()
                continue
            rows.append([direction, float(value), amplitude, gap, force])
    return rows


def _finite(value):
    return value if value is not None and math.isfinite(value) else None


# analysis name -> (options model, the function that runs it into a temporary folder and
# returns its entries of summary.json)
ANALYSES = {"poincare": (PoincareOptions, poincare_map),
            "lyapunov": (LyapunovOptions, lyapunov_exponent),
            "shooting": (ShootingOptions, periodic_orbit),
            "continuation": (ContinuationOptions, continued),
            "bifurcation": (BifurcationOptions, bifurcation_diagram),
            "design": (DesignOptions, design_map)}
