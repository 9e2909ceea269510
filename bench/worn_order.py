"""The worn joint's penetration against the worn joint's FE: the order of its overlap mean.

The Flores joint worn by 1e5 revolutions (build/wear/slider_crank_flores2004/wear.csv) is pushed
along 173.5 degrees in the FE (scenes/fem/flores_worn.toml, build/fem/flores_worn/curve.csv:
the force along the push and across it, per unit length, from the worn surfaces' first touch).
The mechanism's worn joint gives the joint's round FE law (build/fem/flores_wear/curve.csv) at
the penetration delta_p = Phi_0^-1(int d_+^p dphi), times its gradient (docs/theory/wear.md);
this script evaluates that by brute force (400,000 angles, Phi_0 by quadrature) for the
orders 2, 4 (the engine's), 8 and the largest overlap (p -> infinity), pushed from the
surfaces' first touch (one for every order: delta_p > 0 exactly where they overlap), and
writes OUT/worn_order.csv (per order the range of the ratios to the FE's
force along and across the push) and OUT/worn_order.png. Needs `make fem` and `make wear`.
"""

import argparse
import csv
import math
import tomllib
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from pinbore.core.figures import plt, save_png
from pinbore.fem import curve
from pinbore.laws import wearfile
from pinbore.laws.lawsfile import Section

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "fem" / "flores_worn.toml"
ORDERS = [2, 4, 8, math.inf]
ANGLES = 400_000


def round_moment(delta: float, c: float, p: float) -> float:
    """int ((c + delta) cos phi - c)_+^p dphi, by Gauss-Legendre in t = sqrt(delta - d)."""
    x, w = np.polynomial.legendre.leggauss(40)
    t = 0.5 * math.sqrt(delta) * (x + 1)
    return 2 * math.sqrt(delta) * float(np.sum(w * (delta - t * t) ** p / np.sqrt(2 * c + 2 * delta - t * t)))


def main(out: Path) -> None:
    scene = tomllib.loads(SCENE.read_text())
    geometry = scene["geometry"]
    c = geometry["bore_radius"] - geometry["pin_radius"]
    push = math.radians(scene["load"]["direction_deg"])
    along, across = np.array([math.cos(push), math.sin(push)]), np.array([-math.sin(push), math.cos(push)])
    worn = ROOT / "build" / "fem" / "flores_worn" / "curve.csv"
    new = ROOT / "build" / "fem" / "flores_wear" / "curve.csv"
    profiles_file = (SCENE.parent / geometry["wear_file"]).resolve()
    for path in (worn, new, profiles_file):
        if not path.is_file():
            raise SystemExit(f"bench/worn_order.py: {path} is missing: run `make fem wear` first")
    fe = curve.read(worn)
    approach, fe_along, fe_across = fe.approach, fe.force, fe.tangential_force
    new_curve = curve.read(new)
    # the round FE curve as the per-length law a section gives: log-log between its points
    section = Section(curve=str(new), approach_m=new_curve.approach.tolist(),
                      force_N_per_m=new_curve.force.tolist())

    def law(x):
        return float(section.force(x)) if x > 0 else 0.0
    profiles = wearfile.read(profiles_file)
    phi = np.linspace(-math.pi, math.pi, ANGLES, endpoint=False)
    step = phi[1] - phi[0]
    # each profile in its body's frame, placed in the scene's as meshes/worn.py places it
    depth = (wearfile.spline(profiles.bore, phi - math.radians(geometry.get("bore_frame_deg", 0.0)))[0]
             + wearfile.spline(profiles.pin, phi - math.radians(geometry.get("pin_frame_deg", 0.0)))[0])
    u = np.array([np.cos(phi), np.sin(phi)])

    def overlap(s):
        return s * (along @ u) - c - depth

    touch = brentq(lambda s: overlap(s).max(), c, c + 2 * depth.max(), xtol=1e-15)
    rows, lines = [], {}
    for p in ORDERS:
        forces = []
        for a in approach:
            d = overlap(touch + a)
            if math.isinf(p):
                k = int(np.argmax(d))
                force = law(d[k]) * u[:, k]
            else:
                over = np.maximum(d, 0.0)
                moment = step * np.sum(over**p)
                delta = brentq(lambda x: round_moment(x, c, p) - moment, 1e-15, 1e-3, xtol=1e-18, rtol=1e-13)
                h = 1e-6 * delta
                slope = (round_moment(delta + h, c, p) - round_moment(delta - h, c, p)) / (2 * h)
                force = law(delta) * step * p * (u @ over ** (p - 1)) / slope
            forces.append((force @ along, force @ across))
        forces = np.array(forces)
        ratio_along, ratio_across = forces[:, 0] / fe_along, forces[:, 1] / fe_across
        name = "largest overlap" if math.isinf(p) else f"{p:g}"
        lines[name] = forces[:, 0]
        rows.append({"order": name, "first_touch_um": f"{touch * 1e6:.2f}",
                     "along_min": f"{ratio_along.min():.2f}", "along_max": f"{ratio_along.max():.2f}",
                     "across_min": f"{ratio_across.min():.2f}", "across_max": f"{ratio_across.max():.2f}"})
    out.mkdir(parents=True, exist_ok=True)
    with (out / "worn_order.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(approach * 1e6, fe_along / 1e6, "k-", lw=2.5, label="FE, worn")
    ax.plot(approach * 1e6, [law(a) / 1e6 for a in approach], "k:", label="FE, new (the law)")
    for name, force in lines.items():
        ax.plot(approach * 1e6, force / 1e6, label=f"order {name}" if name[0].isdigit() else name)
    ax.set_xlabel("approach from first touch (um)")
    ax.set_ylabel("force along the push (MN/m)")
    ax.legend(fontsize=8)
    save_png(fig, out / "worn_order.png")
    print((out / "worn_order.csv").read_text())


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
