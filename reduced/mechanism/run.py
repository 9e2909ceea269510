"""`pinbore reduced SCENE --out DIR`: integrate a mechanism of any kind with clearance joints.

Writes DIR/timeseries.csv, DIR/summary.json and the plots; a run that blows up (NaN, or a
penetration beyond a tenth of the journal radius or beyond the normal law's range) keeps what
it computed, marks summary.json "incomplete" and exits with 1; a run that breaks a rule of
the verdict (reduced.mechanism.verdict) is marked "suspect" and exits with 1.
"""

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.core.output import atomic_directory
from pinbore.reduced.mechanism import kinds, summary, verdict
from pinbore.reduced.mechanism.layout import (
    BLOWN_UP, DOPRI5, DOPRI5_FIXED, OK, ROSENBROCK23, STEP_TOO_SMALL, TOO_MANY_STEPS)
from pinbore.reduced.mechanism.scene import MAX_STEPS

STATUS = {OK: "complete", BLOWN_UP: "blown up (NaN, or a penetration beyond a tenth of the "
          "journal radius or beyond the normal law's range)", TOO_MANY_STEPS:
          f"more than {MAX_STEPS} steps", STEP_TOO_SMALL: "step size underflow"}
METHODS = {"dopri5": DOPRI5, "dopri5_fixed": DOPRI5_FIXED, "rosenbrock23": ROSENBROCK23}


@dataclass
class Trajectory:
    """What the integrator returns: per accepted step the time, state (q, q', dissipated
    energy, work in, friction states), impact speed and contact mode (1: held) per contact
    and latch flag per torsion element; the impacts (time, joint, approach rate, impulse);
    counters (accepted, rejected, rhs calls, impacts); the status code, the time reached and
    the wall time."""

    times: np.ndarray
    states: np.ndarray
    speeds: np.ndarray
    modes: np.ndarray
    latched: np.ndarray
    impacts: np.ndarray
    counters: np.ndarray
    status: int
    t_end: float
    seconds: float               # of the integration


def onset_tolerance(model) -> float:
    """Penetration (m) within which a contact onset counts as located: 1e-3 of the smallest
    clearance times sqrt(rtol)."""
    return 1e-3 * min((c.gap() for c in model.joints), default=1.0) * model.scene.integrator.rtol ** 0.5


def simulate(model, y0=None, duration=None, args=None) -> Trajectory:
    """Integrate the model from y0 (default: its consistent initial state) over `duration`
    (default: the scene's), with the engine's arguments `args` (default: model.args(), a
    fresh start; the integrator updates their speeds, latches and modes in place)."""
    from pinbore.reduced.mechanism import kernel   # noqa: PLC0415 (the compiled core)
    from pinbore.reduced.mechanism.model import SPEED_FLOOR, fixed_step   # noqa: PLC0415

    s = model.scene.integrator
    y0 = model.y0 if y0 is None else y0
    args = model.args() if args is None else args
    step = fixed_step(model) if s.method == "dopri5_fixed" else s.max_step
    fixed = (METHODS[s.method], s.rtol, s.atol, step, onset_tolerance(model), SPEED_FLOOR, MAX_STEPS)
    start = time.perf_counter()
    result = kernel.integrate(y0, model.scene.duration if duration is None else duration, args,
                              *fixed)
    return Trajectory(**result._asdict(), seconds=time.perf_counter() - start)


def run(scene_path, out) -> int:
    """`pinbore reduced`: a mechanism scene of any kind (reduced.mechanism.kinds)."""
    scene_path = Path(scene_path)
    scene = kinds.load(scene_path)   # validated before the model is built
    from pinbore.reduced.mechanism import outputs   # noqa: PLC0415 (compiled)
    from pinbore.reduced.mechanism.model import build, laws_path   # noqa: PLC0415

    model, trajectory, series, result = summarised(scene, str(scene_path), scene_path.parent)
    twin = None
    if model.joints and scene.output.plots:
        twin_model = build(scene, str(scene_path), scene_path.parent, ideal=True)
        twin = (twin_model, simulate(twin_model))
    with atomic_directory(out, inputs=[laws_path(scene, scene_path.parent)]) as tmp:
        outputs.write_timeseries(tmp / "timeseries.csv", series)
        summary.write(tmp / "summary.json", result)
        if scene.output.plots:
            outputs.plots(tmp, model, series, twin)
    if trajectory.status != OK:
        print(f"pinbore reduced: {scene_path}: stopped at t = {trajectory.t_end:.6g} s: {STATUS[trajectory.status]}; "
              f"kept the time series up to there in {out} (marked incomplete)", file=sys.stderr)
        return 1
    if result.status == "suspect":
        print(f"pinbore reduced: {scene_path}: suspect: {'; '.join(result.verdict)} "
              f"(written to {out}, marked suspect)", file=sys.stderr)
        return 1
    return 0


def summarised(scene, source: str, base: Path):
    """Integrate a validated scene in this process: its model, Trajectory, sampled series
    (outputs.sample) and judged summary (what `pinbore reduced` writes, and what a study's
    point reads without writing files)."""
    from pinbore.reduced.mechanism import outputs   # noqa: PLC0415 (compiled)
    from pinbore.reduced.mechanism.model import build   # noqa: PLC0415

    model = build(scene, source, base)
    trajectory = simulate(model)
    series = outputs.sample(model, trajectory)
    result = judged(outputs.summary(model, series, trajectory, STATUS[trajectory.status], source),
                    scene)
    return model, trajectory, series, result


def judged(result: summary.Summary, scene) -> summary.Summary:
    """The summary with its quality verdict (reduced.mechanism.verdict): a complete run that
    breaks a rule becomes `suspect`."""
    found = verdict.reasons(result, scene)
    status = "suspect" if found and result.status == "complete" else result.status
    return result.model_copy(update={"verdict": found, "status": status})
