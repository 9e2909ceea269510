"""Cost of continuing periodic motions.

1. The impact oscillator's frequency response (scenes/reduced/impact_oscillator.toml), a
   200-point branch over 10-30 Hz through both grazings, its folds and branch points, run in
   this process after a first branch has loaded the engine: at the first step 0.01 of the range (the steps
   adapt, up to 50 times it), and at 0.002 with steps up to 0.005 (a branch of up to 200
   orbits). Counts the maps (one forcing period integrated) the branch takes and where they
   go: the monodromy by central differences at each orbit (2 n + 2 maps, n = 6 coordinates),
   the corrector's iterations and the orbit's measures (one map each), the location of the
   bifurcations. Also times the branch with the Newton tolerance at 10 rtol instead of 100
   rtol (the orbits' accuracy against the corrector's iterations: at 10 rtol the corrector
   meets the noise of the impacts' location).
2. The Flores slider-crank with Coulomb friction (mu 0.1, rtol 4e-8) over its crank's speed,
   both ways from 160 rpm across 155-175 rpm, where its period-1 motion loses stability,
   counted the same way (the difference step the first orbit resolves its multipliers at,
   and that spread); the period doubling against the brute-force attractors 1 rpm either
   side of it, and its doubled orbit against the brute-force period-2 attractor; and one
   monodromy at its first orbit differenced along the tangent space of its joints and drive
   (2 r + 2 maps, r = 4) against one along every coordinate (2 n + 2, n = 18), timed. Then
   the same by the command a user types (with the doubled branch and the direct up- and
   down-sweeps), its result kept in OUT/continuation_slider_crank_flores2004_friction/ for
   the report (the scene it ran beside it, OUT/slider_crank_flores2004_friction.toml).
3. The deployed panel shaken through its hinge (scenes/reduced/deployed_panel_shaken.toml)
   over 3-4 Hz around its first mode, and its spatial twin on the ground, the hinge axis
   vertical (deployed_panel_shaken_3d.toml), by the command a user types (`pinbore dynamics
   --analysis continuation`, with the doubled branches it switches onto and the direct up- and
   down-sweeps): too long for `make` (minutes), so their results are kept here and the report
   shows them.

Writes OUT/continuation.csv (a row per setting), OUT/continuation.png (the oscillator's
branch), OUT/continuation_slider_crank_flores2004_friction/ and
OUT/continuation_deployed_panel_shaken/ and OUT/continuation_deployed_panel_shaken_3d/ (the
continued responses: the command's summary.json, response.png and tables; --keep-panels
takes the panels' rows from their kept results instead of running them again)."""

import argparse
import csv
import dataclasses
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "reduced" / "impact_oscillator.toml"
LOW, HIGH, POINTS, STEP = 10.0, 30.0, 200, 0.01
SLIDER = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
SLIDER_START, SLIDER_RANGE, SLIDER_STEP, SLIDER_POINTS = 160.0, (155.0, 175.0), 0.05, 40
FLIP_TRANSIENT = 300
SLIDER_OPTIONS = ["--parameter", "speed", "--range", "155", "175", "--points", "40", "--step", "1",
                  "--sweeps", "21", "--transient", "30", "--periods", "5"]
PANELS = [(ROOT / "scenes" / "reduced" / "deployed_panel_shaken.toml",
           ["--parameter", "frequency", "--range", "3", "4", "--points", "480", "--step", "0.05",
            "--sweeps", "41", "--transient", "30", "--periods", "5"]),
          (ROOT / "scenes" / "reduced" / "deployed_panel_shaken_3d.toml",
           ["--parameter", "frequency", "--range", "3", "4", "--points", "160", "--step", "0.05",
            "--sweeps", "21", "--transient", "30", "--periods", "5"])]
COLUMNS = ["scene", "tolerance_rtol", "first_step", "largest_step", "points", "wall_time_s", "seconds_per_point", "maps", "maps_per_point",
           "seconds_per_map", "maps_in_monodromies", "maps_in_corrector", "maps_in_locating",
           "bifurcations", "reached", "monodromy_s", "monodromy_every_coordinate_s", "difference_step",
           "start_spread", "brute_force"]


class Counted:
    """A family that counts its maps and measures by what asked for them."""

    def __init__(self, family):
        self.family, self.calls, self.asker = family, {}, "corrector"
        self.tolerance, self.scale = family.tolerance, family.scale
        self.consistent = family.consistent   # a projection onto the joints: no integration

    def map(self, x, p, multiple):
        self.calls[self.asker] = self.calls.get(self.asker, 0) + 1
        return self.family.map(x, p, multiple)

    def measure(self, x, p, multiple):
        self.calls[self.asker] = self.calls.get(self.asker, 0) + 1
        return self.family.measure(x, p, multiple)


def counting(family, low: float, high: float):
    """The continuation of `family` in [low, high], its maps counted by what asked for them
    (a monodromy while locating counts to locating)."""
    from pinbore.reduced.dynamics import continuation

    counted = Counted(family)
    line = continuation.Continuation(counted, low, high)
    jacobian, locate = line.jacobian, line.locate

    def counted_jacobian(*args):
        asker = counted.asker
        counted.asker = "monodromy" if asker == "corrector" else asker
        try:
            return jacobian(*args)
        finally:
            counted.asker = asker

    def counted_locate(*args):
        asker, counted.asker = counted.asker, "locating"
        try:
            return locate(*args)
        finally:
            counted.asker = asker
    line.jacobian, line.locate = counted_jacobian, counted_locate
    return line, counted


def branch(tolerance_factor: float, step: float, largest: float | None = None):
    from pinbore.reduced.dynamics import studies

    data = tomllib.loads(SCENE.read_text())
    start = data["loads"][0]["frequency_hz"]
    family = studies.MechanismFamily(studies.SceneFile(SCENE, data), "frequency", start)
    family.tolerance = tolerance_factor * data["integrator"]["rtol"]
    line, counted = counting(family, LOW, HIGH)
    x = family.settle(start, 30)[1]
    began = time.perf_counter()
    first, _ = line.resolve(line.first(x, start, 1.0))   # as the command does: FD_STEP here
    branches = [line.run(dataclasses.replace(first, tangent=-first.tangent), step, POINTS // 2, ds_max=largest),
                line.run(first, step, POINTS // 2, ds_max=largest)]
    wall = time.perf_counter() - began
    return branches, counted.calls, wall


def row(scene: str, factor: float, step: float, largest: float, branches, calls: dict, wall: float) -> dict:
    points = sum(len(b.points) for b in branches)
    maps = sum(calls.values())
    return {"scene": scene, "tolerance_rtol": factor, "first_step": step, "largest_step": largest,
            "points": points, "wall_time_s": f"{wall:.1f}",
            "seconds_per_point": f"{wall / points:.3f}", "maps": maps,
            "maps_per_point": f"{maps / points:.1f}", "seconds_per_map": f"{wall / maps:.2e}",
            "maps_in_monodromies": calls.get("monodromy", 0),
            "maps_in_corrector": calls.get("corrector", 0),
            "maps_in_locating": calls.get("locating", 0),
            "bifurcations": " ".join(f"{s.kind}@{s.p:.5g}" for b in branches for s in b.specials),
            "reached": f"{max(p.p for b in branches for p in b.points):.5g}"}


def slider_crank() -> dict:
    """The slider-crank with friction continued both ways from SLIDER_START across
    SLIDER_RANGE (the command's procedure: the difference step chosen at the first orbit,
    each way from the first orbit's template), the first period doubling checked against
    the brute-force attractors 1 rpm either side of it (FLIP_TRANSIENT periods settled, then
    20 sampled), and the first orbit's monodromy timed along the joints' tangent space and
    along every coordinate."""
    from pinbore.reduced.dynamics import continuation, flow, studies

    family = studies.MechanismFamily(studies.SceneFile(SLIDER, friction_scene()), "speed", SLIDER_START)
    low, high = SLIDER_RANGE
    line, counted = counting(family, low, high)
    state, x, _ = family.settle(SLIDER_START, 10)
    family.template = template = state
    began = time.perf_counter()
    first, spread = line.resolve(line.first(x, SLIDER_START, 1.0))
    branches = []
    for direction in (-1.0, 1.0):
        family.template = template
        branches.append(line.run(dataclasses.replace(first, tangent=direction * first.tangent),
                                 SLIDER_STEP, SLIDER_POINTS // 2))
    wall = time.perf_counter() - began
    result = row("slider_crank_flores2004 mu 0.1, speed", 100, SLIDER_STEP, 50 * SLIDER_STEP, branches,
                 counted.calls, wall)
    result |= {"difference_step": f"{line.step:g}", "start_spread": f"{spread:.2g}"}
    flips = sorted((s for b in branches for s in b.specials if s.kind == "period_doubling"), key=lambda s: s.p)
    if flips:
        result["brute_force"] = flip_checked(family, line, flips[0])
    plain = continuation.Continuation(family, low, high)
    began = time.perf_counter()
    plain.jacobian(first.x, first.p)
    result["monodromy_s"] = f"{time.perf_counter() - began:.2f}"
    family.consistent = None   # no projection known: every coordinate is differenced
    began = time.perf_counter()
    plain.jacobian(first.x, first.p)
    result["monodromy_every_coordinate_s"] = f"{time.perf_counter() - began:.2f}"
    return result


def flip_checked(family, line, flip) -> str:
    """The period doubling at `flip` against the brute-force attractors 1 rpm either side of
    it (FLIP_TRANSIENT periods from the scene's start, then 20 sampled): their periods, and
    the distance (um) of the brute-force period-2 attractor's two points from those of the
    doubled orbit (switched onto at the flip, continued, and converged by Newton at that
    speed), the journal's centre in its bore at the section."""
    import numpy as np

    from pinbore.reduced.dynamics import continuation, flow

    doubled = line.doubled(flip, SLIDER_STEP, 10)
    said = []
    for speed in (round(flip.p) - 1.0, round(flip.p) + 1.0):
        here = family.flow(speed)
        samples, states = flow.poincare(here, here.start(), FLIP_TRANSIENT, 20)
        period = flow.period_of(samples)
        said.append(f"{speed:g} rpm: period {period}")
        if speed > flip.p and period == 2 and doubled is not None:
            twice = continuation.Continuation(family, line.low, line.high, 2)
            twice.step = line.step
            near = min(doubled.points, key=lambda p: abs(p.p - speed))
            orbit = family.state(here, twice.first(near.x, speed, 1.0).x)
            ours = [here.observed(s)[:2] for s in (orbit, here.advance(orbit))]
            theirs = [here.observed(s)[:2] for s in states[-2:]]
            off = max(min(np.linalg.norm(a - b) for b in theirs) for a in ours)
            said[-1] += f", {off * 1e6:.2g} um from the doubled orbit"
    return "; ".join(said)


def friction_scene() -> dict:
    """The Flores slider-crank with Coulomb friction (mu 0.1) at SLIDER_START, rtol 4e-8."""
    data = tomllib.loads(SLIDER.read_text())
    data["drive"]["speed_rpm"] = SLIDER_START
    data["clearance_joints"][0]["friction"] = {"law": "coulomb_ambrosio", "mu": 0.1}
    data["integrator"]["rtol"] = 4e-8
    return data


def command(scene: Path, options: list[str], folder: Path, label: str) -> dict:
    """A continued response by the command a user types (its summary.json, response.png and
    tables in `folder`), as a row (command_row)."""
    import subprocess

    began = time.time()
    scene = scene.relative_to(ROOT) if scene.is_relative_to(ROOT) else scene   # as a user names it
    done = subprocess.run([sys.executable, "-m", "pinbore.cli", "dynamics", str(scene),
                           "--analysis", "continuation", *options, "--out", str(folder)], cwd=ROOT)
    written = (folder / "summary.json").is_file() and (folder / "summary.json").stat().st_mtime >= began
    if done.returncode not in (0, 1) or not written:   # 1 with a summary: a branch marked partial
        raise SystemExit(f"{label}: the continuation failed (exit {done.returncode})")
    return command_row(folder, options, label)


def command_row(folder: Path, options: list[str], label: str) -> dict:
    """The row of a continued response the command wrote in `folder` with `options`: its own
    counts (its maps are not counted)."""
    import json

    s = json.loads((folder / "summary.json").read_text())
    low, high = (float(v) for v in options[options.index("--range") + 1:][:2])
    step = float(options[options.index("--step") + 1]) / (high - low)   # of the range
    values = [float(v) for v in csv_column(folder / "continuation.csv", "value")]
    return {"scene": f"{label} (the command, with sweeps)",
            "tolerance_rtol": 100, "first_step": step, "largest_step": 50 * step, "points": s["points"],
            "wall_time_s": f"{s['wall_time_s']:.1f}", "seconds_per_point": f"{s['seconds_per_point']:.3f}",
            "bifurcations": " ".join(f"{b['kind']}@{b['value']:.5g}" for b in s["bifurcations"]),
            "reached": f"{max(values):.5g}", "difference_step": s.get("difference_step", ""),
            "start_spread": f"{s['start_multiplier_spread']:.2g}"}


def csv_column(path: Path, name: str) -> list[str]:
    with open(path, newline="") as f:
        return [r[name] for r in csv.DictReader(f)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--keep-panels", action="store_true",
                        help="the shaken panels' rows from their results kept in OUT (not run again: "
                             "over an hour)")
    args = parser.parse_args()
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    branch(100, STEP)   # a first branch loads the engine and its imports before timing
    for factor, step, largest in ((100, STEP, None), (100, STEP / 5, STEP / 2), (10, STEP, None)):
        branches, calls, wall = branch(factor, step, largest)
        rows.append(row("impact_oscillator, frequency", factor, step, largest or 50 * step, branches, calls, wall))
        print(rows[-1], file=sys.stderr)
        if (factor, step) == (100, STEP):
            picture(branches, out / "continuation.png")
    rows.append(slider_crank())
    print(rows[-1], file=sys.stderr)
    import tomli_w

    scene = out / "slider_crank_flores2004_friction.toml"   # the scene it ran, kept beside
    scene.write_text("# bench/continuation.py: scenes/reduced/slider_crank_flores2004.toml with Coulomb "
                     "friction (mu 0.1), at 160 rpm, rtol 4e-8\n" + tomli_w.dumps(friction_scene()))
    rows.append(command(scene.resolve(), SLIDER_OPTIONS, out / "continuation_slider_crank_flores2004_friction",
                        "slider_crank_flores2004 mu 0.1, speed"))
    print(rows[-1], file=sys.stderr)
    for scene, options in PANELS:
        kept, label = out / f"continuation_{scene.stem}", f"{scene.stem}, frequency"
        rows.append(command_row(kept, options, label) if args.keep_panels
                    else command(scene, options, kept, label))
        print(rows[-1], file=sys.stderr)
    with open(out / "continuation.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return 0


def picture(branches, path: Path) -> None:
    from pinbore.core.figures import plt, save_png

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for b in branches:
        ax.plot([p.p for p in b.points], [p.measures["amplitude"] * 1e3 for p in b.points], ".-", ms=3)
        for s in b.specials:
            ax.plot(s.p, s.point.measures["amplitude"] * 1e3, "o", mfc="none", ms=8)
            ax.annotate(s.kind.replace("_", " "), (s.p, s.point.measures["amplitude"] * 1e3), fontsize=7)
    ax.set_xlabel("forcing frequency (Hz)")
    ax.set_ylabel("amplitude across the guide (mm)")
    ax.set_title("impact oscillator: the continued branch, a dot per orbit", fontsize=9)
    ax.grid(alpha=0.3)
    save_png(fig, path, layout=True)


if __name__ == "__main__":
    sys.exit(main())
