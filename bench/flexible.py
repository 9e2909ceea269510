"""Benchmark of flexible bodies in the mechanism: run time against the rigid model, and the
answer against the modes kept.

1. Rigid against flexible at the same tolerance: each shipped flexible scene (the Flores
   slider-crank with the flexible link of scenes/modes/link_steel_2d, 4 crank revolutions; the
   planar deployment with its flexible panel; the 3D deployment with its flexible panel and
   FE-calibrated hinge: the whole pipeline) against its rigid twin, the same scene with the
   body rigid of its modes file's mass and inertia (reduced.mechanism.flexible.rigid_twin:
   every joint, law and tolerance the same, so the difference is what flexibility costs).
   Wall time of the integration (compiled code loaded: each run twice, the second timed),
   steps, right-hand sides, the peak contact force.
   The fastest free motion (the largest |eigenvalue| of the linearised equations of motion
   at a state out of contact) and the steps the run took a period of it on average: what
   sets a flexible run's step.
2. Mode truncation: the slider-crank's flexible rod reduced with 20 fixed-interface modes,
   kept 1 .. 20 of its free modes: the peak contact force, the rod's largest mid-span
   deflection and the wall time; the spin-up beam's peak tip deflection (hub frame) with
   1 .. 6 fixed-interface modes in its basis.

Writes OUT/flexible.csv, OUT/flexible_truncation.csv and OUT/flexible.png. Needs the modes
of the shipped bodies (make modes).
"""

import argparse
import csv
import re
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.fem.modes import file as modes_file
from pinbore.core.cpp.mechanism import spin_up
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.flexible import rigid_twin

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes" / "reduced"
FLEXIBLE = ["slider_crank_flores2004_flexible", "solar_panel_deployment_flexible",
            "solar_panel_deployment_3d_flexible"]
LINK_MODES = [1, 2, 4, 6, 8, 12, 16, 20]


def scene_data(name: str) -> dict:
    return tomllib.loads((SCENES / f"{name}.toml").read_text())


def timed(data: dict) -> tuple:
    """(model, trajectory, wall time of the second run)."""
    model = build(kinds.validate(data, "bench"), "bench", SCENES)
    simulate(model)
    start = time.perf_counter()
    trajectory = simulate(model)
    return model, trajectory, time.perf_counter() - start


def peak_force(model, trajectory) -> float:
    cols = per_step(model, trajectory)[0]
    return max(float(np.max(v)) for k, v in cols.items() if k.endswith("_normal_force_N"))


def fastest_motion(model, trajectory) -> float:
    """The largest |lambda| (rad/s) of the Jacobian df/dy of the equations of motion (central
    differences of the right-hand side) at the first recorded state with no contact force
    (the shipped flexible scenes: their start, undeformed): the fastest free motion an
    integrator resolves, a flexible body's stiffest kept mode as its joints constrain it.
    (Of a rigid mechanism it would measure the constraints' Baumgarte terms, not a motion.)"""
    from pinbore.reduced.mechanism import kernel

    args = model.args()
    for t, y in zip(trajectory.times, trajectory.states):
        if not np.any(kernel.rhs_value(t, y, args)[1]):
            break
    else:
        raise RuntimeError("no recorded state is out of contact")
    jacobian = np.empty((y.size, y.size))
    for i in range(y.size):
        h = 1e-7 * max(abs(y[i]), 1e-3)
        up, down = y.copy(), y.copy()
        up[i] += h
        down[i] -= h
        jacobian[:, i] = (kernel.rhs_value(t, up, args)[0] - kernel.rhs_value(t, down, args)[0]) / (2 * h)
    return float(np.abs(np.linalg.eigvals(jacobian)).max())


def against_rigid() -> list[dict]:
    """Each flexible scene and its rigid twin: rows (rigid, flexible) in turn."""
    rows = []
    for name in FLEXIBLE:
        flexible = scene_data(name)
        for data, is_flexible in ((rigid_twin(flexible, SCENES), False), (flexible, True)):
            model, trajectory, wall = timed(data)
            rows.append({"scene": name, "flexible": is_flexible, "wall_s": wall,
                         "steps": trajectory.times.size, "rhs": int(trajectory.counters[2]),
                         "rhs_us": 1e6 * wall / trajectory.counters[2],
                         "peak_force_N": peak_force(model, trajectory)})
            if is_flexible:   # the step against the period of the fastest free motion
                fastest = fastest_motion(model, trajectory)
                rows[-1] |= {"fastest_rad_per_s": fastest, "steps_per_period":
                             2 * np.pi / fastest * trajectory.times.size / model.scene.duration}
        ratio = rows[-1]["wall_s"] / rows[-2]["wall_s"]
        print(f"{name}: {rows[-1]['wall_s']:.3f} s, {ratio:.1f} x its rigid twin "
              f"({rows[-1]['steps']} against {rows[-2]['steps']} steps, "
              f"{rows[-1]['rhs_us']:.2f} against {rows[-2]['rhs_us']:.2f} us a right-hand side); "
              f"its fastest free motion {rows[-1]['fastest_rad_per_s']:.3g} rad/s, "
              f"{rows[-1]['steps_per_period']:.1f} steps a period on average")
    return rows


def link_truncation(out: Path) -> list[dict]:
    """The slider-crank with the link reduced to 20 fixed-interface modes, 1 .. 20 kept."""
    text = (ROOT / "scenes" / "modes" / "link_steel_2d.toml").read_text()
    most = max(LINK_MODES)
    text = re.sub(r"(?m)^fixed_interface_modes = \d+", f"fixed_interface_modes = {most}", text)
    text = re.sub(r"(?m)^modes = \d+", f"modes = {most}", text)
    work = (out / "flexible_link").resolve()
    work.mkdir(exist_ok=True)
    (work / "link.toml").write_text(text)
    subprocess.run([sys.executable, "-m", "pinbore.cli", "modes", str(work / "link.toml"), "--out",
                    str(work / "modes")], check=True)
    path = work / "modes" / "body.npz"
    reduced = modes_file.read(path)
    rows = []
    for n in LINK_MODES:
        scene = scene_data("slider_crank_flores2004_flexible")
        scene["bodies"][1].update(modes_file=str(path), modes=n)
        model, trajectory, wall = timed(scene)
        cols = per_step(model, trajectory)[0]
        rows.append({"body": "link", "modes": n, "highest_mode_rad_per_s": float(reduced.omega[n - 1]),
                     "peak_force_N": peak_force(model, trajectory),
                     "mid_deflection_m": float(np.abs(cols["rod_mid_uy_m"]).max()),
                     "wall_s": wall, "steps": trajectory.times.size})
        print(f"link, {n} modes: peak {rows[-1]['peak_force_N']:.4g} N in {wall:.2f} s")
    shutil.rmtree(work)
    return rows


def spin_up_truncation(out: Path) -> list[dict]:
    """The spin-up beam reduced with 1 .. 6 fixed-interface modes, all its free modes kept (a
    clamped beam's deflection needs the whole Craig-Bampton basis: its free-free modes alone
    are no cantilever's; dropping free modes of a 6-mode basis lost 29 % of the peak)."""
    text = (ROOT / "scenes" / "modes" / "spinup_beam_2d.toml").read_text()
    work = (out / "flexible_beam").resolve()
    work.mkdir(exist_ok=True)
    rows = []
    for n in range(1, 7):
        basis = re.sub(r"(?m)^fixed_interface_modes = \d+", f"fixed_interface_modes = {n}", text)
        basis = re.sub(r"(?m)^modes = \d+", f"modes = {n}", basis)
        (work / f"beam{n}.toml").write_text(basis)
        subprocess.run([sys.executable, "-m", "pinbore.cli", "modes", str(work / f"beam{n}.toml"),
                        "--out", str(work / f"modes{n}")], check=True)
        scene = scene_data("flexible_spinup_beam")
        scene["bodies"][0]["modes_file"] = str(work / f"modes{n}" / "body.npz")
        model, trajectory, wall = timed(scene)
        cols = per_step(model, trajectory)[0]
        drive = model.scene.drive
        theta = np.array([spin_up(t, drive.speed, drive.spin_up_s)[0] for t in cols["time_s"]])
        deflection = -np.sin(theta) * cols["beam_tip_x_m"] + np.cos(theta) * cols["beam_tip_y_m"]
        rows.append({"body": "spin-up beam", "modes": n, "peak_deflection_m": float(-deflection.min()),
                     "wall_s": wall, "steps": trajectory.times.size})
        print(f"spin-up beam, {n} fixed-interface modes: peak tip deflection "
              f"{rows[-1]['peak_deflection_m']:.4f} m")
    shutil.rmtree(work)
    return rows


def write(path: Path, rows: list[dict]) -> None:
    keys = list(dict.fromkeys(k for row in rows for k in row))
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, keys)
        writer.writeheader()
        writer.writerows(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    rigid = against_rigid()
    link, beam = link_truncation(out), spin_up_truncation(out)
    write(out / "flexible.csv", rigid)
    write(out / "flexible_truncation.csv", link + beam)
    draw(out, rigid, link, beam)
    print(f"wrote {out / 'flexible.csv'}, {out / 'flexible_truncation.csv'}, {out / 'flexible.png'}")


def draw(out: Path, rigid: list[dict], link: list[dict], beam: list[dict]) -> None:
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
    ax = axes[0]
    labels = {"slider_crank_flores2004_flexible": "slider-crank",
              "solar_panel_deployment_flexible": "deployment",
              "solar_panel_deployment_3d_flexible": "3D deployment"}
    pairs = [(r, f) for r, f in zip(rigid[0::2], rigid[1::2])]
    x = np.arange(len(pairs))
    ax.bar(x - 0.2, [r["wall_s"] for r, _ in pairs], 0.4, label="rigid twin")
    ax.bar(x + 0.2, [f["wall_s"] for _, f in pairs], 0.4, label="flexible")
    for k, (r, f) in enumerate(pairs):
        ax.text(k + 0.2, f["wall_s"], f"{f['wall_s'] / r['wall_s']:.0f}x", ha="center", va="bottom")
    ax.set_xticks(x, [labels.get(r["scene"], r["scene"]) for r, _ in pairs])
    ax.set_ylabel("integration wall time (s)")
    ax.set_title("rigid against flexible, same tolerance")
    ax.legend()
    ax = axes[1]
    ax.plot([r["modes"] for r in link], [r["peak_force_N"] / 1e3 for r in link], "o-")
    ax.axhline(rigid[0]["peak_force_N"] / 1e3, color="k", ls="--", lw=1, label="rigid rod")
    ax.set_xlabel("modes of the rod kept")
    ax.set_ylabel("peak contact force (kN)")
    ax.set_title("slider-crank: truncation")
    ax.legend()
    ax.grid(alpha=0.3)
    ax = axes[2]
    ax.plot([r["modes"] for r in beam], [r["peak_deflection_m"] for r in beam], "o-")
    ax.set_xlabel("fixed-interface modes of the beam's basis")
    ax.set_ylabel("peak tip deflection, hub frame (m)")
    ax.set_title("spin-up beam: truncation")
    ax.grid(alpha=0.3)
    save_png(fig, out / "flexible.png", layout=True)


if __name__ == "__main__":
    main()
