"""`pinbore wear SCENE --out DIR`: Archard wear of a planar mechanism's revolute clearance
joint over `cycles` periods of its forcing, on the contact pressure of the joint's FE run.

The mechanism is integrated as its scene says; a cycle's wear is the mean of its forcing
periods after the first (its transient; the last one alone in a run of less than two). Writes
DIR/wear.csv (the bore's and the pin's worn depth against the angle of each surface's own
frame), DIR/summary.json (volumes, deepest wear and where, the sliding distance and the loads
against the FE run's range) and DIR/wear.png.
"""

import math
import sys
from pathlib import Path

import numpy as np

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.laws import wearfile
from pinbore.reduced.wear import history, pressure, profile
from pinbore.reduced.wear import summary as wear_summary
from pinbore.reduced.wear.scene import WearScene

RADIUS_MATCH = 1e-6   # relative: the FE run's radii are the joint's


def resolved(base: Path, name: str) -> Path:
    path = Path(name)
    return path if path.is_absolute() else base / path


def mechanism_of(scene: WearScene, base: Path, source: str):
    """(the mechanism scene, its path, the joint, its forcing period), checked: a planar
    mechanism whose joint `joint` is a revolute clearance joint, run over at least a period."""
    from pinbore.reduced.mechanism import kinds   # noqa: PLC0415

    path = resolved(base, scene.mechanism_file)
    mechanism = kinds.load(path)
    if kinds.of_scene(mechanism).name != "planar":
        raise InputError(f"{source}: mechanism_file: a planar mechanism (kind = \"reduced\") is "
                         "needed: the wear of a spatial joint is not modelled")
    joints = {c.name: c for c in mechanism.clearance_joints}
    if scene.joint not in joints:
        raise InputError(f"{source}: joint: {scene.joint!r} is not a revolute clearance joint of "
                         f"{path} (it has: {', '.join(joints) or 'none'})")
    try:
        period = mechanism.forcing_period()
    except ValueError as err:
        raise InputError(f"{source}: mechanism_file: {err}") from None
    if mechanism.duration < period * (1 - 1e-12):
        raise InputError(f"{source}: mechanism_file: duration {mechanism.duration:g} s is shorter "
                         f"than one forcing period ({period:g} s), the cycle worn")
    return mechanism, path, joints[scene.joint], period


def check_radii(table, joint, source: str) -> None:
    """The FE run is of the joint: its pin's and bore's radii are the joint's."""
    for name, fe, mine in (("pin", table.pin_radius, joint.journal_radius),
                           ("bore", table.bore_radius, joint.bearing_radius)):
        if abs(fe - mine) > RADIUS_MATCH * mine:
            raise InputError(f"{source}: pressure_file: its FE run's {name} radius {fe:g} m is not "
                             f"the joint {joint.name}'s ({mine:g} m): run the FE of this joint")


def run(scene_path, out) -> int:
    scene_path = Path(scene_path)
    source = str(scene_path)
    scene = scenes.load(WearScene, scene_path)
    base = scene_path.parent
    mechanism, mechanism_path, joint, period = mechanism_of(scene, base, source)
    table = pressure.read(resolved(base, scene.pressure_file), resolved(base, scene.curve_file), source)
    check_radii(table, joint, source)
    from pinbore.reduced.mechanism.model import build, laws_path   # noqa: PLC0415
    from pinbore.reduced.mechanism.run import STATUS, simulate   # noqa: PLC0415

    model = build(mechanism, str(mechanism_path), mechanism_path.parent)
    trajectory = simulate(model)
    if trajectory.status != 0:
        print(f"pinbore wear: {mechanism_path}: the mechanism stopped at t = {trajectory.t_end:.6g} s "
              f"({STATUS[trajectory.status]}): no cycle to wear by; nothing written", file=sys.stderr)
        return 1
    j = [c.name for c in model.joints].index(scene.joint)
    end = trajectory.times[-1]
    periods = averaged_periods(end, period)
    cycle = history.of_run(model, trajectory, j, (end - periods * period, end))
    worn = wear(scene, table, cycle, periods)
    result = summary(scene, source, mechanism_path, table, cycle, worn, period, periods)
    if result.extrapolated:
        print(f"pinbore wear: {source}: the joint's load reaches {result.peak_force_per_length_N_per_m:.4g} N/m, "
              f"beyond the FE run's {table.forces[-1]:.4g} N/m: the pressure there is the last "
              "step's scaled (extrapolated)", file=sys.stderr)
    inputs = [mechanism_path, laws_path(mechanism, mechanism_path.parent)]
    with atomic_directory(out, inputs=[p for p in inputs if p is not None]) as tmp:
        wearfile.write(tmp / "wear.csv", wearfile.Profiles(np.degrees(worn["angles"]), worn["bore"], worn["pin"]))
        wear_summary.write(tmp / wear_summary.SUMMARY, result)
        picture(tmp / "wear.png", worn, joint, scene)
    return 0


def averaged_periods(end: float, period: float) -> int:
    """How many forcing periods at the end of a run of `end` seconds a cycle's wear is the mean
    of: every whole period but the first (its transient), at least the last one."""
    return max(int(math.floor(end / period * (1 + 1e-12))) - 1, 1)


def wear(scene: WearScene, table, cycle, periods: int) -> dict:
    """The worn depth of the bore and of the pin after scene.cycles cycles (m), on the angles
    of each surface's frame (rad): the history's wear (over `periods` periods) per period,
    times the cycles."""
    at = profile.angles(scene.points)
    load = cycle.force / scene.length
    times = scene.cycles / periods
    return {"angles": at,
            "bore": times * profile.worn_depth(table, cycle.time, load, cycle.bore_angle,
                                                      cycle.sliding_speed, scene.bore.wear_coefficient,
                                                      at, table.bore_radius),
            "pin": times * profile.worn_depth(table, cycle.time, load, cycle.pin_angle,
                                                     cycle.sliding_speed, scene.pin.wear_coefficient,
                                                     at, table.pin_radius)}


def summary(scene, source, mechanism_path, table, cycle, worn, period,
            periods: int) -> wear_summary.WearSummary:
    """What summary.json holds."""
    peak = float(np.max(cycle.force)) / scene.length
    slid = float(np.trapezoid(np.abs(cycle.sliding_speed) * (cycle.force > 0), cycle.time)) / periods
    surfaces = {}
    for name, radius in (("bore", table.bore_radius), ("pin", table.pin_radius)):
        depth = worn[name]
        k = int(np.argmax(depth))
        surfaces[name] = {"wear_coefficient_m2_per_N": getattr(scene, name).wear_coefficient,
                          "volume_m3": profile.volume_per_length(depth, radius) * scene.length,
                          "max_depth_m": float(depth[k]), "at_deg": math.degrees(worn["angles"][k])}
    return wear_summary.WearSummary(
        scene_file=source, mechanism_file=str(mechanism_path), joint=scene.joint,
        cycles=scene.cycles, period_s=period, periods_averaged=periods, length_m=scene.length,
        sliding_distance_in_contact_per_cycle_m=slid, peak_force_per_length_N_per_m=peak,
        fe_force_range_N_per_m=[0.0, float(table.forces[-1])],
        extrapolated=bool(peak > table.forces[-1]), **surfaces)


def picture(path: Path, worn: dict, joint, scene) -> None:
    """The worn depths against angle, and the worn bore and pin drawn (depth exaggerated)."""
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    fig = plt.figure(figsize=(11, 4.5))
    ax = fig.add_subplot(1, 2, 1)
    degrees = np.degrees(worn["angles"])
    ax.plot(degrees, worn["bore"] * 1e6, label="bore")
    ax.plot(degrees, worn["pin"] * 1e6, label="pin")
    ax.set_xlabel("angle in the surface's frame (deg)")
    ax.set_ylabel("worn depth (um)")
    ax.set_title(f"{scene.joint}: after {scene.cycles:.3g} cycles")
    ax.legend()
    px = fig.add_subplot(1, 2, 2, projection="polar")
    deepest = max(worn["bore"].max(), worn["pin"].max(), 1e-30)
    scale = 0.2 * joint.bearing_radius / deepest   # the deepest wear drawn at a fifth of the radius
    ring = np.append(worn["angles"], worn["angles"][0])
    closed = lambda d: np.append(d, d[0])   # noqa: E731
    px.plot(ring, np.full(ring.size, joint.bearing_radius) * 1e3, "k:", lw=0.8, label="new")
    px.plot(ring, (joint.bearing_radius + scale * closed(worn["bore"])) * 1e3, label="worn bore (bore frame)")
    px.plot(ring, (joint.journal_radius - scale * closed(worn["pin"])) * 1e3, label="worn pin (pin frame)")
    px.set_title(f"depth x {scale:.3g}", fontsize=9)
    px.legend(loc="lower left", fontsize=8, bbox_to_anchor=(-0.2, -0.15))
    save_png(fig, path, layout=True)
