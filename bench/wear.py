"""Cost against accuracy of the coupled wear's cycle jumping: the Flores slider-crank's
rod-slider joint over 1e5 crank revolutions (scenes/wear/slider_crank_flores2004_coupled.toml)
at jump tolerances of 20, 10, 5 and 2.5 um, and one-way (the new joint's motion throughout).
Per run: wall time, jumps kept and refused, mechanism runs, the bore's and the pin's deepest
wear and worn volume, and the profiles' largest difference from the tightest run's, relative
to its deepest wear. The mechanism is chaotic: a run's rate of wear (the mean of its
revolutions after the first) scatters, and so do the jumps; the tolerance bounds that
scatter's effect too.
Writes OUT/wear.csv and OUT/wear.png. Needs the joint's FE run (make fem).
"""

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import tomli_w

from pinbore.core.figures import plt, save_png
from pinbore.laws import wearfile

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "wear" / "slider_crank_flores2004_coupled.toml"
TOLERANCES = [20e-6, 10e-6, 5e-6, 2.5e-6]


def run(data: dict, folder: Path, name: str) -> dict:
    """`pinbore wear` on the scene data (its files made absolute): wall time, summary, profiles."""
    from pinbore.core.scene import absolute_files

    scene = folder / f"{name}.toml"
    scene.write_text(tomli_w.dumps(absolute_files(data, SCENE.parent)))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pinbore.cli", "wear", str(scene), "--out", str(folder / name)],
                   check=True, capture_output=True)
    wall = time.perf_counter() - start
    return {"wall": wall, "summary": json.loads((folder / name / "summary.json").read_text()),
            "profiles": wearfile.read(folder / name / "wear.csv")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    base = tomllib.loads(SCENE.read_text())
    runs = {}
    with tempfile.TemporaryDirectory(prefix="pinbore-bench-wear-") as folder:
        folder = Path(folder)
        one_way = {k: v for k, v in base.items() if k != "coupling"}
        runs["one-way"] = run(one_way, folder, "one_way")
        for tolerance in TOLERANCES:
            data = base | {"coupling": {"tolerance": tolerance}}
            runs[f"{tolerance * 1e6:g} um"] = run(data, folder, f"tol_{tolerance * 1e6:g}")
            print(f"{tolerance * 1e6:g} um: {runs[f'{tolerance * 1e6:g} um']['wall']:.1f} s", file=sys.stderr)
    reference = runs[f"{TOLERANCES[-1] * 1e6:g} um"]["profiles"]
    deepest = max(reference.bore.max(), reference.pin.max())
    rows = []
    for name, r in runs.items():
        s, p = r["summary"], r["profiles"]
        difference = max(np.abs(p.bore - reference.bore).max(), np.abs(p.pin - reference.pin).max())
        rows.append({"run": name, "wall_time_s": f"{r['wall']:.1f}", "jumps": len(s["jumps"]) - 1 if s["coupled"] else 0,
                     "refused": s["refused_jumps"], "mechanism_runs": s["mechanism_runs"],
                     "bore_max_depth_um": f"{s['bore']['max_depth_m'] * 1e6:.1f}",
                     "pin_max_depth_um": f"{s['pin']['max_depth_m'] * 1e6:.1f}",
                     "bore_volume_mm3": f"{s['bore']['volume_m3'] * 1e9:.2f}",
                     "difference_from_tightest": f"{difference / deepest:.3f}"})
    with open(out / "wear.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    for name, r in runs.items():
        p = r["profiles"]
        ax.plot(p.angle_deg, p.bore * 1e6, lw=0.9, label=name)
    ax.set_xlabel("angle in the bore's frame (deg)")
    ax.set_ylabel("bore's worn depth after 1e5 revolutions (um)")
    ax.legend(fontsize=8)
    coupled = [r for r in rows if r["run"] != "one-way"]
    bx.plot([float(r["wall_time_s"]) for r in coupled], [float(r["difference_from_tightest"]) for r in coupled], "o-")
    for r in coupled:
        bx.annotate(r["run"], (float(r["wall_time_s"]), float(r["difference_from_tightest"])), fontsize=8)
    bx.set_xlabel("wall time (s)")
    bx.set_ylabel("largest profile difference / deepest wear")
    bx.set_title("cycle jumping: cost against the tightest tolerance's profile")
    save_png(fig, out / "wear.png", layout=True)


if __name__ == "__main__":
    main()
