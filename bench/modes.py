"""Benchmark of the modal reduction (pinbore modes): run time against size, and the error
against the modes kept.

1. The shipped panel (scenes/modes/panel_aluminium_3d.toml) at three mesh sizes: the wall
   time of each step of the reduction (mesh and assembly, the fixed-interface modes with
   the constraint modes, the reduced body's modes, the geometric stiffening) against the
   dofs, and the error of the reduced body's first eight frequencies against the whole
   model's (its interfaces tied alike) and of the first held-interface frequency against
   the finest mesh.
2. Mode truncation: the shipped link and the panel with 2, 4, 8, 16 fixed-interface modes:
   the largest error of the first kept frequencies against the whole model.

Writes OUT/modes.csv, OUT/modes_truncation.csv and OUT/modes.png. Serial (one process).
"""

import argparse
import csv
import time
import tomllib
from pathlib import Path

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.fem.modes import reduction
from pinbore.fem.modes.scene import ModesScene

ROOT = Path(__file__).resolve().parent.parent
PANEL = ROOT / "scenes" / "modes" / "panel_aluminium_3d.toml"
LINK = ROOT / "scenes" / "modes" / "link_steel_2d.toml"
PANEL_CELLS = [0.05, 0.04, 0.03]     # m; 0.03 is the shipped panel's
FIXED = [2, 4, 8, 16]


def scene_with(path: Path, body=None, reduction_=None) -> ModesScene:
    data = tomllib.loads(path.read_text())
    data["body"].update(body or {})
    data["reduction"].update(reduction_ or {})
    return ModesScene.model_validate(data)


def timed(scene: ModesScene) -> tuple[reduction.Reduced, float]:
    start = time.perf_counter()
    reduced = reduction.reduce(scene)
    return reduced, time.perf_counter() - start


def sizes(out: Path) -> list[dict]:
    rows = []
    for cell in PANEL_CELLS:
        reduced, wall = timed(scene_with(PANEL, {"cell_size": cell}))
        s = reduced.seconds
        rows.append({"cell_size_m": cell, "dofs": reduced.dofs,
                     "mesh_and_assembly_s": s["mesh_and_assembly"],
                     "fixed_interface_modes_s": s["fixed_interface_modes"],
                     "reduced_modes_s": s["reduced_modes"], "stiffening_s": s["stiffening"],
                     "reduction_s": wall - s["full_modes"], "whole_model_modes_s": s["full_modes"],
                     "max_reduction_error": float(np.max(np.abs(reduced.omega / reduced.full_omega - 1))),
                     "first_held_Hz": reduced.fixed_interface_omega[0] / (2 * np.pi)})
        print(f"panel cell {cell} m: {reduced.dofs} dofs, reduction {rows[-1]['reduction_s']:.1f} s")
    finest = rows[-1]["first_held_Hz"]
    for r in rows:
        r["first_held_error_vs_finest"] = r["first_held_Hz"] / finest - 1
    write(out / "modes.csv", rows)
    return rows


def truncation(out: Path) -> list[dict]:
    rows = []
    for name, path in (("link_steel_2d", LINK), ("panel_aluminium_3d", PANEL)):
        for fixed in FIXED:
            scene = scene_with(path, reduction_={"fixed_interface_modes": fixed, "modes": 1})
            keep = min(tomllib.loads(path.read_text())["reduction"]["modes"], scene.most_modes)
            scene = scene_with(path, reduction_={"fixed_interface_modes": fixed, "modes": keep,
                                                 "full_modes": keep})
            reduced, wall = timed(scene)
            error = reduced.omega / reduced.full_omega - 1
            rows.append({"body": name, "fixed_interface_modes": fixed, "modes": keep,
                         "error_mode1": float(error[0]), "max_error": float(np.max(error)),
                         "reduction_s": wall - reduced.seconds["full_modes"]})
            print(f"{name}: {fixed} fixed-interface modes: first {error[0]:.2e}, largest "
                  f"{np.max(error):.2e} over {keep}")
    write(out / "modes_truncation.csv", rows)
    return rows


def write(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(out: Path, size_rows, truncation_rows) -> None:
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.5))
    dofs = [r["dofs"] for r in size_rows]
    for key, label in (("mesh_and_assembly_s", "mesh and assembly"),
                       ("fixed_interface_modes_s", "fixed-interface and constraint modes"),
                       ("stiffening_s", "geometric stiffening"), ("reduction_s", "the whole reduction")):
        a.plot(dofs, [r[key] for r in size_rows], "o-", label=label)
    a.axhline(20, color="k", ls=":", lw=1, label="20 s")
    a.set_xlabel("dofs (panel, P2 tetrahedra)")
    a.set_ylabel("wall time (s)")
    a.set_title("reduction of the panel, one process")
    a.grid(alpha=0.3)
    a.legend(fontsize=8)
    for body in dict.fromkeys(r["body"] for r in truncation_rows):
        rows = [r for r in truncation_rows if r["body"] == body]
        b.semilogy([r["fixed_interface_modes"] for r in rows], [r["max_error"] for r in rows],
                   "o-", label=f"{body}: largest of the kept modes")
        b.semilogy([r["fixed_interface_modes"] for r in rows], [r["error_mode1"] for r in rows],
                   "s--", label=f"{body}: first mode")
    b.set_xlabel("fixed-interface modes kept")
    b.set_ylabel("reduced / whole model - 1")
    b.set_title("mode truncation")
    b.grid(alpha=0.3, which="both")
    b.legend(fontsize=8)
    save_png(fig, out / "modes.png", layout=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    plot(args.out, sizes(args.out), truncation(args.out))


if __name__ == "__main__":
    main()
