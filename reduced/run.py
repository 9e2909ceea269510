"""`pinbore reduced SCENE --out DIR`: integrate a mechanism with clearance joints.

Writes DIR/timeseries.csv, DIR/summary.json and the plots; a run that blows up (NaN, or a
penetration beyond a tenth of the journal radius or beyond the normal law's range) keeps what
it computed, marks summary.json "incomplete" and exits with 1.
"""

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.core import scene as scenes
from pinbore.core.output import atomic_directory
from pinbore.reduced import kernel, outputs, summary, verdict
from pinbore.reduced.layout import JOINT_CLEARANCE
from pinbore.reduced.model import SPEED_FLOOR, Model, build, fixed_step, laws_path
from pinbore.reduced.scene import MAX_STEPS, ReducedScene

STATUS = {kernel.OK: "complete", kernel.BLOWN_UP: "blown up (NaN, or a penetration beyond a "
          "tenth of the journal radius or beyond the normal law's range)", kernel.TOO_MANY_STEPS:
          f"more than {MAX_STEPS} steps", kernel.STEP_TOO_SMALL: "step size underflow"}


METHODS = {"dopri5": kernel.DOPRI5, "dopri5_fixed": kernel.DOPRI5_FIXED,
           "rosenbrock23": kernel.ROSENBROCK23}


@dataclass
class Trajectory:
    """What the integrator returns: per accepted step the time, state (q, q', dissipated
    energy, work in, friction states), impact speed and contact mode (1: held) per clearance
    joint and latch flag per torsion element; the impacts (time, joint, approach rate,
    impulse); counters (accepted, rejected, rhs calls, impacts); the status code, the time
    reached and the wall time."""

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
    compile_seconds: float = 0.0   # of numba's compilation (or cache load) before it, if any


def onset_tolerance(model: Model) -> float:
    """Penetration (m) within which a contact onset counts as located."""
    return (1e-3 * min(model.joints[:, JOINT_CLEARANCE], default=1.0)
            * model.scene.integrator.rtol ** 0.5)


def simulate(model: Model, y0=None, duration=None, args=None) -> Trajectory:
    """Integrate the model from y0 (default: its consistent initial state) over `duration`
    (default: the scene's), with the kernel arguments `args` (default: model.kernel_args(),
    a fresh start; the integrator updates their speeds, latches and modes in place)."""
    s = model.scene.integrator
    y0 = model.y0 if y0 is None else y0
    args = model.kernel_args() if args is None else args
    step = fixed_step(model) if s.method == "dopri5_fixed" else s.max_step
    fixed = (METHODS[s.method], s.rtol, s.atol, step, onset_tolerance(model), SPEED_FLOOR, MAX_STEPS)
    start = time.perf_counter()
    # the first run of this process and kind of mechanism compiles (or loads); later, this
    # returns at once
    kernel.integrate(y0, 0.0, model.kernel_args(), *fixed)
    compiled = time.perf_counter()
    result = kernel.integrate(y0, model.scene.duration if duration is None else duration, args,
                              *fixed)
    return Trajectory(**result._asdict(), seconds=time.perf_counter() - compiled,
                      compile_seconds=compiled - start)


def ideal_twin(scene: ReducedScene) -> ReducedScene:
    """The same mechanism with every clearance joint replaced by an ideal revolute."""
    joints = list(scene.joints) + [
        {"type": "revolute", "body_i": c.bearing_body, "point_i": c.bearing_point,
         "body_j": c.journal_body, "point_j": c.journal_point} for c in scene.clearance_joints]
    data = scene.model_dump()
    data["joints"] = [j if isinstance(j, dict) else j.model_dump() for j in joints]
    data["clearance_joints"] = []
    return ReducedScene.model_validate(data)


def run(scene_path, out) -> int:
    """`pinbore reduced`: a planar (kind = "reduced") or spatial (kind = "spatial") scene."""
    scene_path = Path(scene_path)
    if scenes.read_toml(scene_path).get("kind") == "spatial":
        from pinbore.reduced import spatial_model, spatial_outputs
        scene = scenes.load(spatial_model.SpatialScene, scene_path)
        builder, writer, twin_of = spatial_model.build, spatial_outputs, spatial_model.ideal_twin
    else:
        scene = scenes.load(ReducedScene, scene_path)
        builder, writer, twin_of = build, outputs, ideal_twin
    model = builder(scene, str(scene_path), scene_path.parent)
    trajectory = simulate(model)
    twin = None
    if scene.clearance_joints and scene.output.plots:
        twin_model = builder(twin_of(scene), str(scene_path), scene_path.parent)
        twin = (twin_model, simulate(twin_model))
    with atomic_directory(out, inputs=[laws_path(scene, scene_path.parent)]) as tmp:
        series = writer.sample(model, trajectory)
        outputs.write_timeseries(tmp / "timeseries.csv", series)
        result = judged(writer.summary(model, series, trajectory, STATUS[trajectory.status],
                                       str(scene_path)), scene)
        summary.write(tmp / "summary.json", result)
        if scene.output.plots:
            writer.plots(tmp, model, series, twin)
    if trajectory.status != kernel.OK:
        print(f"pinbore reduced: {scene_path}: stopped at t = {trajectory.t_end:.6g} s: {STATUS[trajectory.status]}; "
              f"kept the time series up to there in {out} (marked incomplete)", file=sys.stderr)
        return 1
    if result.status == "suspect":
        print(f"pinbore reduced: {scene_path}: suspect: {'; '.join(result.verdict)} "
              f"(written to {out}, marked suspect)", file=sys.stderr)
        return 1
    return 0


def judged(result: summary.Summary, scene: ReducedScene) -> summary.Summary:
    """The summary with its quality verdict (reduced/verdict.py): a complete run that breaks a
    rule becomes `suspect`."""
    found = verdict.reasons(result, scene)
    status = "suspect" if found and result.status == "complete" else result.status
    return result.model_copy(update={"verdict": found, "status": status})
