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
import tempfile
from pathlib import Path

import numpy as np

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.laws import wearfile
from pinbore.reduced.wear import history, jumping, pressure, profile
from pinbore.reduced.wear import summary as wear_summary
from pinbore.reduced.wear.scene import WearScene

RADIUS_MATCH = 1e-6   # relative: the FE run's radii are the joint's


def mechanism_of(scene: WearScene, base: Path, source: str):
    """(the mechanism scene, its path, the joint, its forcing period), checked: a planar
    mechanism whose joint `joint` is a revolute clearance joint, run over at least a period
    (over `periods` of them if the scene says so)."""
    from pinbore.reduced.mechanism import kinds   # noqa: PLC0415

    path = scenes.named_file(scene.mechanism_file, base)
    data = scenes.read_toml(path)
    mechanism = kinds.validate(data, str(path))
    if kinds.of_scene(mechanism).name != "planar":
        raise InputError(f"{source}: mechanism_file: a planar mechanism (kind = \"planar\") is "
                         "needed: the wear of a spatial joint is not modelled")
    joints = {c.name: c for c in mechanism.clearance_joints}
    if scene.joint not in joints:
        raise InputError(f"{source}: joint: {scene.joint!r} is not a revolute clearance joint of "
                         f"{path} (it has: {', '.join(joints) or 'none'})")
    try:
        period = mechanism.forcing_period()
    except ValueError as err:
        raise InputError(f"{source}: mechanism_file: {err}") from None
    if scene.periods is not None:   # the mechanism run over that many periods
        try:
            mechanism = kinds.validate(data | {"duration": scene.periods * period}, str(path))
        except InputError as err:
            raise InputError(f"{source}: periods: {scene.periods} periods of {period:g} s: {err}") from None
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
    table = pressure.read(scenes.named_file(scene.pressure_file, base), scenes.named_file(scene.curve_file, base),
                          source)
    check_radii(table, joint, source)
    from pinbore.reduced.mechanism.model import laws_path   # noqa: PLC0415

    kernel = None
    if scene.compliance_file is not None:   # coupling.pressure = "worn" (the scene's rule)
        from pinbore.fem import compliance   # noqa: PLC0415

        kernel = compliance.read(scenes.named_file(scene.compliance_file, base))

    at = profile.angles(scene.points)
    try:
        with tempfile.TemporaryDirectory(prefix="pinbore-wear-") as folder:
            cycle = Cycle(scene, mechanism, mechanism_path, table, period, at, Path(folder), kernel)
            if scene.coupling is None:
                rates, last = cycle(None)
                worn = {"angles": at, "bore": scene.cycles * rates["bore"], "pin": scene.cycles * rates["pin"]}
                jumps = None
            else:
                depth, jumps = jumping.jump(
                    lambda h: joined(*cycle(split(h))), np.zeros(2 * at.size), scene.cycles,
                    scene.coupling.tolerance, scene.coupling.first_jump or scene.cycles / 20,
                    record=lambda h, info: jump_record(split(h), info, table, scene.length))
                last = cycle.last
                worn = {"angles": at} | split(depth)
    except Stopped as err:
        print(f"pinbore wear: {mechanism_path}: {err}: nothing written", file=sys.stderr)
        return 1
    result = summary(scene, source, mechanism_path, table, last, worn, period, cycle.periods, jumps,
                     (cycle.solves, cycle.narrow))
    if cycle.narrow:
        print(f"pinbore wear: {source}: {cycle.narrow} of the worn joint's {cycle.solves} contacts "
              f"solved press fewer than {pressure.NARROW} points of the compliance's "
              f"{360 / kernel.size:g} degree grid: the pressure there, and the wear it lays, "
              "are not resolved (docs/theory/wear.md)", file=sys.stderr)
    if result.extrapolated:
        print(f"pinbore wear: {source}: the joint's load reaches {result.peak_force_per_length_N_per_m:.4g} N/m, "
              f"beyond the FE run's {table.forces[-1]:.4g} N/m: the pressure there is the last "
              "step's scaled (extrapolated)", file=sys.stderr)
    inputs = [mechanism_path, laws_path(mechanism, mechanism_path.parent)]
    with atomic_directory(out, inputs=[p for p in inputs if p is not None]) as tmp:
        wearfile.write(tmp / "wear.csv", wearfile.Profiles(np.degrees(worn["angles"]), worn["bore"], worn["pin"]))
        wear_summary.write(tmp / wear_summary.SUMMARY, result)
        picture(tmp / "wear.png", worn, joint, scene, result)
    return 0


class Stopped(Exception):
    """The mechanism did not run to its end."""


class Cycle:
    """The wear of one cycle (m per cycle, bore and pin, on `at`) of the joint worn by given
    profiles (None: new): the mechanism run on them (its joint's wear_file a wear.csv in
    `folder`), its periods after the first averaged; `last` the last run's joint history.
    With the FE run's surface compliance `kernel`, the pressure on given profiles is the worn
    joint's own (wear.pressure.worn_tables), else the FE table's."""

    def __init__(self, scene, mechanism, mechanism_path, table, period, at, folder: Path,
                 kernel=None):
        self.scene, self.mechanism, self.path, self.table = scene, mechanism, mechanism_path, table
        self.kernel = kernel
        self.period, self.at, self.folder = period, at, folder
        self.last, self.periods = None, 1
        self.solves = self.narrow = 0   # the worn joint's loads solved, and those unresolved

    def __call__(self, worn: dict | None):
        from pinbore.reduced.mechanism.model import build   # noqa: PLC0415
        from pinbore.reduced.mechanism.run import STATUS, simulate   # noqa: PLC0415

        mechanism = self.mechanism
        if worn is not None:
            path = self.folder / "wear.csv"
            wearfile.write(path, wearfile.Profiles(np.degrees(self.at), worn["bore"], worn["pin"]))
            joints = [c.model_copy(update={"wear_file": str(path)}) if c.name == self.scene.joint else c
                      for c in mechanism.clearance_joints]
            mechanism = mechanism.model_copy(update={"clearance_joints": joints})
        model = build(mechanism, str(self.path), self.path.parent)
        trajectory = simulate(model)
        if trajectory.status != 0:
            raise Stopped(f"the mechanism stopped at t = {trajectory.t_end:.6g} s "
                          f"({STATUS[trajectory.status]})" + ("" if worn is None else
                                                               " on the worn joint"))
        j = [c.name for c in model.joints].index(self.scene.joint)
        end = trajectory.times[-1]
        self.periods = averaged_periods(end, self.period)
        self.last = cycle = history.of_run(model, trajectory, j, (end - self.periods * self.period, end))
        load = cycle.force / self.scene.length
        tables = None
        if worn is not None and self.kernel is not None:
            from pinbore.fem.compliance import Conformal   # noqa: PLC0415

            joint = Conformal(self.kernel, self.table.pin_radius, self.table.bore_radius,
                              worn["bore"], worn["pin"])
            try:
                tables = pressure.worn_tables(joint, self.table, load, cycle.bore_angle, cycle.pin_angle)
            except ArithmeticError as err:
                raise Stopped(f"the worn joint's contact pressure: {err}") from None
            self.solves, self.narrow = self.solves + tables.solves, self.narrow + tables.narrow
        rates = {name: profile.worn_depth(self.table, cycle.time, load, angle, cycle.sliding_speed,
                                          getattr(self.scene, name).wear_coefficient, self.at, radius,
                                          None if tables is None else getattr(tables, name))
                       / self.periods
                 for name, angle, radius in (("bore", cycle.bore_angle, self.table.bore_radius),
                                             ("pin", cycle.pin_angle, self.table.pin_radius))}
        return rates, cycle


def joined(rates: dict, cycle) -> tuple:
    """A cycle's rates as one vector, bore then pin (split's inverse), and its history."""
    return np.concatenate([rates["bore"], rates["pin"]]), cycle


def split(h: np.ndarray) -> dict:
    """The bore's and the pin's halves of a jump's depth vector."""
    half = h.size // 2
    return {"bore": h[:half], "pin": h[half:]}


def jump_record(worn: dict, cycle, table, length: float) -> dict:
    """What a kept jump records of the joint at its end: the deepest wear of each surface, the
    bore's worn volume and, of the run on it, the peak contact force of
    a cycle and the largest force of its first impact."""
    return {"bore_max_depth_m": float(np.max(worn["bore"])), "pin_max_depth_m": float(np.max(worn["pin"])),
            "volume_m3": profile.volume_per_length(worn["bore"], table.bore_radius) * length,
            "peak_force_N": float(np.max(cycle.force)), "first_impact_force_N": cycle.first_impact}


def averaged_periods(end: float, period: float) -> int:
    """How many forcing periods at the end of a run of `end` seconds a cycle's wear is the mean
    of: every whole period but the first (its transient), at least the last one."""
    return max(int(math.floor(end / period * (1 + 1e-12))) - 1, 1)


def summary(scene, source, mechanism_path, table, cycle, worn, period, periods: int,
            jumps, contacts=(0, 0)) -> wear_summary.WearSummary:
    """What summary.json holds (the joint's history `cycle`: the last run's; `contacts`: the
    worn joint's loads solved over the runs, and those narrower than the compliance's grid)."""
    peaks = [float(np.max(cycle.force))] + ([] if jumps is None else [r["peak_force_N"] for r in jumps.records])
    peak = max(peaks) / scene.length   # over every run of the worn joint
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
        extrapolated=bool(peak > table.forces[-1]) and scene.compliance_file is None, **surfaces,
        coupled=jumps is not None, pressure="new" if scene.compliance_file is None else "worn",
        mechanism_runs=1 if jumps is None else jumps.runs,
        worn_contacts_solved=contacts[0], worn_contacts_unresolved=contacts[1],
        refused_jumps=0 if jumps is None else jumps.refused,
        jumps=[] if jumps is None else [
            wear_summary.Jump(cycles=n, size=d, error_m=e, **r)
            for n, d, e, r in zip(jumps.cycles, jumps.sizes, jumps.errors, jumps.records)])


def picture(path: Path, worn: dict, joint, scene, result) -> None:
    """The worn depths against angle, the worn bore and pin drawn (depth exaggerated), and,
    coupled, the deepest wear, the bore's worn volume, the peak contact force of a cycle and
    the first impact's against the cycles."""
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    panels = 3 if result.coupled else 2
    fig = plt.figure(figsize=(5.5 * panels, 4.5))
    ax = fig.add_subplot(1, panels, 1)
    degrees = np.degrees(worn["angles"])
    ax.plot(degrees, worn["bore"] * 1e6, label="bore")
    ax.plot(degrees, worn["pin"] * 1e6, label="pin")
    ax.set_xlabel("angle in the surface's frame (deg)")
    ax.set_ylabel("worn depth (um)")
    ax.set_title(f"{scene.joint}: after {scene.cycles:.3g} cycles" + (" (coupled)" if result.coupled else ""))
    ax.legend()
    px = fig.add_subplot(1, panels, 2, projection="polar")
    deepest = max(worn["bore"].max(), worn["pin"].max(), 1e-30)
    scale = 0.2 * joint.bearing_radius / deepest   # the deepest wear drawn at a fifth of the radius
    ring = np.append(worn["angles"], worn["angles"][0])
    closed = lambda d: np.append(d, d[0])   # noqa: E731
    px.plot(ring, np.full(ring.size, joint.bearing_radius) * 1e3, "k:", lw=0.8, label="new")
    px.plot(ring, (joint.bearing_radius + scale * closed(worn["bore"])) * 1e3, label="worn bore (bore frame)")
    px.plot(ring, (joint.journal_radius - scale * closed(worn["pin"])) * 1e3, label="worn pin (pin frame)")
    px.set_title(f"depth x {scale:.3g}", fontsize=9)
    px.legend(loc="lower left", fontsize=8, bbox_to_anchor=(-0.2, -0.15))
    if result.coupled:
        cx = fig.add_subplot(1, panels, 3)
        n = [j.cycles for j in result.jumps]
        cx.plot(n, [j.bore_max_depth_m * 1e6 for j in result.jumps], "o-", ms=3, label="bore, deepest (um)")
        cx.plot(n, [j.pin_max_depth_m * 1e6 for j in result.jumps], "s-", ms=3, label="pin, deepest (um)")
        cx.set_xlabel("cycles")
        cx.set_ylabel("worn depth (um), volume (mm^3)")
        cx.plot(n, [j.volume_m3 * 1e9 for j in result.jumps], "d-", ms=3, label="bore's worn volume (mm^3)")
        fx = cx.twinx()
        fx.plot(n, [j.peak_force_N / 1e3 for j in result.jumps], "k^--", ms=3, label="peak force of a cycle (kN)")
        fx.plot(n, [j.first_impact_force_N / 1e3 for j in result.jumps], "kv:", ms=3, label="first impact's force (kN)")
        fx.set_ylabel("contact force (kN)")
        cx.legend(loc="upper left", fontsize=8)
        fx.legend(loc="lower right", fontsize=8)
        cx.set_title(f"{len(result.jumps) - 1} jumps, {result.mechanism_runs} runs")
    save_png(fig, path, layout=True)
