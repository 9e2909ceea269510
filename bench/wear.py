"""Cost against accuracy of the coupled wear's cycle jumping, the Flores slider-crank's rod-slider
joint over 1e5 crank revolutions, on two mechanisms:

- chaotic: the shipped scene (scenes/wear/slider_crank_flores2004_coupled.toml, 5000 rpm,
  frictionless) at jump tolerances of 20, 10, 5 and 2.5 um, and one-way (the new joint's
  motion throughout). A run's rate of wear (the mean of its revolutions after the first)
  scatters, and so do the jumps; the tolerance bounds that scatter's effect too.
- periodic: the same joint at 150 rpm with Coulomb friction (mu 0.1), its slider pulled by a
  soft spring (bench/slider_crank_flores2004_loaded.toml: in contact throughout after the first
  revolution; 3 revolutions a run), at 2.5, 1, 0.5, 0.25 and 0.125 um.

Every coupled run wears by the new joint's FE pressure (the shipped scene's); one more run
of the periodic mechanism, at a tolerance of its ladder, by the worn joint's own pressure
(coupling.pressure = "worn"): how far the pressure's model moves the profile against how far
the jumps do.

Per run: wall time, jumps kept and refused, mechanism runs, the bore's and the pin's deepest
wear and worn volume, and the bore's and the pin's profiles' largest difference from the
tightest run's of their mechanism, relative to its deepest wear of that surface, with the
worn volume's relative difference.
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
LOADED = ROOT / "bench" / "slider_crank_flores2004_loaded.toml"
COMPLIANCE = ROOT / "build" / "fem" / "flores_wear" / "compliance.csv"
# mechanism -> (its wear scene's changes, one-way too, the jump tolerances (m))
# and the tolerance of its one run by the worn joint's own pressure (None: none; a rattling
# joint meets its bore at thousands of pairs of directions, each solved: minutes a run)
LADDERS = {"chaotic": ({}, True, [20e-6, 10e-6, 5e-6, 2.5e-6], None),
           "periodic": ({"mechanism_file": str(LOADED), "periods": 3}, False,
                        [2.5e-6, 1e-6, 0.5e-6, 0.25e-6, 0.125e-6], 2.5e-6)}


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


def ladder(base: dict, one_way: bool, tolerances, worn_at: float | None, folder: Path, name: str) -> dict:
    """The runs of one mechanism: one-way if asked, coupled on the worn joint's own pressure at
    `worn_at` if given, then on the new joint's at each tolerance (the tightest last: the
    reference)."""
    runs = {}
    common = {k: v for k, v in base.items() if k not in ("coupling", "compliance_file")}
    if one_way:
        runs["one-way"] = run(common, folder, f"{name}_one_way")
    plan = [] if worn_at is None else [(worn_at, "worn", f"{worn_at * 1e6:g} um, worn joint's pressure")]
    plan += [(t, "new", f"{t * 1e6:g} um") for t in tolerances]
    for tolerance, pressure, label in plan:
        data = common | {"coupling": {"tolerance": tolerance, "pressure": pressure}}
        if pressure == "worn":
            data["compliance_file"] = str(COMPLIANCE)
        runs[label] = run(data, folder, f"{name}_{pressure}_tol_{tolerance * 1e6:g}")
        print(f"{name}, {label}: {runs[label]['wall']:.1f} s", file=sys.stderr)
    return runs


def rows_of(name: str, runs: dict, reference: str) -> list[dict]:
    """The table's rows of one mechanism's runs against its run `reference`."""
    ref = runs[reference]
    rows = []
    for label, r in runs.items():
        s, p = r["summary"], r["profiles"]
        differences = {f"{surface}_difference": f"{np.abs(getattr(p, surface) - getattr(ref['profiles'], surface)).max() / getattr(ref['profiles'], surface).max():.4f}"
                       for surface in ("bore", "pin")}
        rows.append({"mechanism": name, "run": label, "wall_time_s": f"{r['wall']:.1f}",
                     "jumps": len(s["jumps"]) - 1 if s["coupled"] else 0,
                     "refused": s["refused_jumps"], "mechanism_runs": s["mechanism_runs"],
                     "bore_max_depth_um": f"{s['bore']['max_depth_m'] * 1e6:.2f}",
                     "pin_max_depth_um": f"{s['pin']['max_depth_m'] * 1e6:.2f}",
                     "bore_volume_mm3": f"{s['bore']['volume_m3'] * 1e9:.4f}", **differences,
                     "volume_difference": f"{s['bore']['volume_m3'] / ref['summary']['bore']['volume_m3'] - 1:.5f}"})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    base = tomllib.loads(SCENE.read_text())
    rows, ladders = [], {}
    with tempfile.TemporaryDirectory(prefix="pinbore-bench-wear-") as folder:
        for name, (changes, one_way, tolerances, worn_at) in LADDERS.items():
            ladders[name] = ladder(base | changes, one_way, tolerances, worn_at, Path(folder), name)
            rows += rows_of(name, ladders[name], f"{tolerances[-1] * 1e6:g} um")
    with open(out / "wear.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    for ax, (name, surface) in zip(axes[:2], (("chaotic", "bore"), ("periodic", "pin"))):
        for label, r in ladders[name].items():
            if "worn joint" in label:
                continue
            ax.plot(r["profiles"].angle_deg, getattr(r["profiles"], surface) * 1e6, lw=0.9, label=label)
        ax.set_xlabel(f"angle in the {surface}'s frame (deg)")
        ax.set_ylabel(f"{surface}'s worn depth after 1e5 revolutions (um)")
        ax.set_title(f"{name} mechanism")
        ax.legend(fontsize=8)
    bx = axes[2]
    for name in LADDERS:
        coupled = [r for r in rows if r["mechanism"] == name and r["run"].endswith(" um")][:-1]
        for surface, mark in (("bore", "o-"), ("pin", "s--")):
            bx.loglog([float(r["wall_time_s"]) for r in coupled], [float(r[f"{surface}_difference"]) for r in coupled],
                      mark, label=f"{name}, {surface}")
    bx.set_xlabel("wall time (s)")
    bx.set_ylabel("largest profile difference / deepest wear")
    bx.set_title("against the tightest tolerance's profile")
    bx.legend(fontsize=8)
    save_png(fig, out / "wear.png", layout=True)


if __name__ == "__main__":
    main()
