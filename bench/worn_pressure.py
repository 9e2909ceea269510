"""The worn joint's contact on the FE's surface compliance against the worn joint's own FE run.

The Flores joint worn by 1e5 revolutions (build/wear/slider_crank_flores2004/wear.csv) is pushed
along 173.5 degrees in the FE on a mesh of its worn surfaces (scenes/fem/flores_worn.toml,
build/fem/flores_worn: the force per unit length and the pressure at each push step). The same
push on the new joint's surface compliance (build/fem/flores_wear/compliance.csv,
fem.compliance.Conformal.pushed: the exact rigid gap of the worn surfaces, the pin's centre
moved as far along the push from their first touch) gives per step: the force along the push
against the FE's, the pressure's centre (its mean angle from the push) against the FE's, and
the difference of the pressures' forces in 5 degree bins over the largest bin. And the time of
a load-controlled solve (Conformal.loaded, the pin free) against the FE run's. Writes
OUT/worn_pressure.csv and OUT/worn_pressure.png. Needs `make fem` and `make wear`.
"""

import argparse
import csv
import json
import math
import time
import tomllib
from pathlib import Path

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.core.scene import load_json
from pinbore.fem import compliance, curve
from pinbore.fem.scene import FemScene, worn_joint

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "fem" / "flores_worn.toml"
NEW = ROOT / "build" / "fem" / "flores_wear"
WORN = ROOT / "build" / "fem" / "flores_worn"
BINS = np.arange(-60.0, 60.1, 5.0)   # deg from the push


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    from pinbore.core.scene import validate

    scene = validate(FemScene, tomllib.loads(SCENE.read_text()), str(SCENE))
    worn = worn_joint(scene, SCENE.parent, str(SCENE))
    g = scene.geometry
    joint = compliance.Conformal(compliance.read(NEW / "compliance.csv"), g.pin_radius, g.bore_radius,
                                 worn.bore_depth, worn.pin_depth)
    direction = math.radians(scene.load.direction_deg)
    u = np.array([math.cos(direction), math.sin(direction)])
    touch = worn.touch(scene.load.direction_deg)[0]
    points = joint.facing(direction, 0.0)
    fe, pressure = curve.read(WORN / "curve.csv"), curve.read_pressure(WORN / "pressure.csv")
    rows, shown = [], []
    for step, approach, force in zip(fe.step, fe.approach, fe.force):
        p, theta = joint.pushed((touch + approach) * u, 0.0, points)
        alpha = np.degrees(np.remainder(theta - direction + math.pi, 2 * math.pi) - math.pi)
        arc = g.bore_radius * np.abs(np.gradient(np.unwrap(theta)))   # the bore's arc of each point
        mine = g.bore_radius * joint.spacing * p            # N/m: each point's force
        mine_force = float(np.sum(mine * np.cos(np.radians(alpha))))
        at = pressure.step == step
        order = np.argsort(pressure.angle[at])
        theirs = arc * np.interp(alpha, pressure.angle[at][order], pressure.pressure[at][order], left=0.0, right=0.0)
        binned = [np.histogram(alpha, BINS, weights=w)[0] for w in (mine, theirs)]
        p = joint.on_bore(p, theta)
        start = time.perf_counter()
        joint.loaded(float(force), direction, 0.0)
        solve = time.perf_counter() - start
        rows.append({"step": int(step), "approach_um": f"{approach * 1e6:.1f}",
                     "force_ratio": f"{mine_force / force:.4f}",
                     "centre_deg": f"{np.sum(alpha * mine) / np.sum(mine):.2f}",
                     "fe_centre_deg": f"{np.sum(alpha * theirs) / np.sum(theirs):.2f}",
                     "bins_difference": f"{np.sqrt(np.mean((binned[0] - binned[1]) ** 2)) / binned[1].max():.4f}",
                     "solve_ms": f"{solve * 1e3:.2f}"})
        shown.append((approach, alpha, p, theirs / arc))
    fe_time = load_json(WORN / "result.json", "fem", "the worn FE run's result.json")["wall_time_s"]["total"]
    rows[-1]["fe_run_s"] = f"{fe_time:.1f}"
    with open(out / "worn_pressure.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=[*rows[0], "fe_run_s"], restval="")
        writer.writeheader()
        writer.writerows(rows)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for approach, alpha, p, theirs in shown[1::max(len(shown) // 4, 1)]:
        order = np.argsort(alpha)
        line, = axes[0].plot(alpha[order], p[order] / 1e6, lw=1.0, label=f"compliance, {approach * 1e6:.0f} um")
        axes[0].plot(alpha[order], theirs[order] / 1e6, "--", color=line.get_color(), lw=1.0, label="worn FE")
    axes[0].set_xlim(-60, 60)
    axes[0].set_xlabel("angle from the push (deg)")
    axes[0].set_ylabel("contact pressure (MPa)")
    axes[0].legend(fontsize=7)
    approaches = [float(r["approach_um"]) for r in rows]
    axes[1].plot(approaches, [float(r["force_ratio"]) for r in rows], "o-", label="force, of the FE's")
    axes[1].plot(approaches, [1 + float(r["bins_difference"]) for r in rows], "s--", label="1 + binned pressure's difference")
    axes[1].set_xlabel("approach beyond first touch (um)")
    axes[1].legend(fontsize=8)
    axes[1].set_title(f"a load: {np.median([float(r['solve_ms']) for r in rows]):.1f} ms; the worn FE run: {fe_time:.0f} s")
    save_png(fig, out / "worn_pressure.png", layout=True)
    print(json.dumps({"steps": len(rows)}))


if __name__ == "__main__":
    main()
