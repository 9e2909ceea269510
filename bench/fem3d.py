"""Benchmark of the 3D FE contact: run time against error over mesh levels, MPI speed-up,
and the cost of friction.

A steel pin (R = 10 mm, c = 10 um) in a bore 20 mm long, pushed 10 um in 5 load steps,
augmented Lagrangian, half model (mid-plane symmetry). Each level refines the section
(contact element size) and the layers together by about sqrt(2). Writes OUT/fem3d.csv and
OUT/fem3d.png:

- wall time of the whole `pinbore fem` command, dofs, Newton iterations (sum and median
  per step);
- force error at the largest approach against the mesh-converged force: Richardson
  extrapolation of the three finest levels with their observed order when they converge
  monotonically (column reference_order), else against the finest level ("finest");
- the finest level again on 2 MPI ranks (speed-up), and level 2 with Coulomb friction
  (mu = 0.2, the same push: the cost of friction);
- LU factorisations against linear solves (Newton iterations): the solver keeps its factors
  while they serve (fem.solver);
- a (delta, theta) path of 20 points on 2 ranks: the shipped 3D study's 20 mm steel lug and
  its mesh, pushed in 10 steps and tilted in 10 (the load programme a calibration runs).

--large adds a level of about 200k dofs on 2 ranks (some 7 minutes).
"""

import argparse
import json
import math
import tempfile
from pathlib import Path

import numpy as np
from fem2d import finish, run, write_table

from pinbore.core.figures import plt
from pinbore.study import point_scene

ROOT = Path(__file__).resolve().parent.parent
SCENE = {
    "kind": "fem",
    "geometry": {"dim": 3, "pin_radius": 9.99e-3, "bore_radius": 10.0e-3, "housing_radius": 0.2,
                 "hub_radius": 2.0e-3, "length": 0.02},
    "materials": {"pin": {"E": 210e9, "nu": 0.3}, "bore": {"E": 210e9, "nu": 0.3}},
    "contact": {"method": "augmented-lagrangian", "friction": 0.0},
    "load": {"max_approach": 1.0e-5, "steps": 5, "direction_deg": -90.0},
    "output": {"picture": False},
}
LEVELS = [(6e-4, 4), (4.2e-4, 6), (3e-4, 8), (2.1e-4, 11), (1.5e-4, 16)]
LARGE = (1.06e-4, 23)
REFINEMENT = math.sqrt(2)   # of the element sizes from level to level
PATH_POINT = (ROOT / "studies" / "calibration_3d.toml", "study3d_steel_steel_L20mm")
PATH_STEPS = 10             # push steps, and as many tilt steps


def path_scene() -> dict:
    """The 3D calibration study's scene of the 20 mm steel lug with a (delta, theta) path of
    2 PATH_STEPS points."""
    scene = point_scene(*PATH_POINT)
    scene["load"].update(steps=PATH_STEPS, tilt_steps=PATH_STEPS)
    scene["output"] = {"picture": False}
    return scene


def scene_at(level, friction=0.0) -> dict:
    size, layers = level
    scene = json.loads(json.dumps(SCENE))
    scene["mesh"] = {"contact_size": size, "grading": 0.5, "layers": layers}
    scene["contact"]["friction"] = friction
    return scene


def main(out: Path, large: bool) -> None:
    cases = [(f"level {i}", level, 1, 0.0) for i, level in enumerate(LEVELS)]
    cases += [(f"level {len(LEVELS) - 1}", LEVELS[-1], 2, 0.0), ("level 2, mu = 0.2", LEVELS[2], 1, 0.2)]
    if large:
        cases.append(("large", LARGE, 2, 0.0))
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, (name, level, ranks, mu) in enumerate(cases):
            print(f"[{i + 1}/{len(cases)}] {name}, {ranks} rank(s)", flush=True)
            records.append((name, level, ranks, mu, run(scene_at(level, mu), Path(tmp), f"case{i}", ranks)))
        print(f"(delta, theta) path of {2 * PATH_STEPS} points, 2 ranks", flush=True)
        path = run(path_scene(), Path(tmp), "path", 2)
    levels = {r[1]: r[4]["force"][-1] for r in records if r[3] == 0.0}   # any ranks
    f1, f2, f3 = [levels[level] for level in sorted(levels, reverse=True)][-3:]
    order = math.log(abs(f1 - f2) / abs(f2 - f3)) / math.log(REFINEMENT)
    # Richardson when the three finest converge monotonically, else the finest as reference
    monotone = (f1 - f2) * (f2 - f3) > 0 and order > 0
    limit = f3 + (f3 - f2) / (REFINEMENT**order - 1) if monotone else f3
    walls = {(r[1], r[2], r[3]): r[4]["wall"] for r in records}
    rows = []
    for name, level, ranks, mu, r in records:
        its = r["result"]["newton_iterations"]
        speedup = walls[(level, 1, mu)] / r["wall"] if ranks > 1 and (level, 1, mu) in walls else None
        cost = r["wall"] / walls[(level, 1, 0.0)] if mu else None
        rows.append([name, level[0], level[1], ranks, mu, r["result"]["dofs"], f"{r['wall']:.1f}",
                     sum(its), f"{np.median(its):g}", sum(r["result"]["factorizations"]),
                     f"{r['force'][-1]:.6e}",
                     "" if mu else f"{abs(r['force'][-1] / limit - 1):.2e}",
                     f"{order:.2f}" if monotone else "finest",
                     "" if speedup is None else f"{speedup:.2f}", "" if cost is None else f"{cost:.2f}"])
    mesh = path["result"]["scene"]["mesh"]
    its = path["result"]["newton_iterations"]
    rows.append([f"path of {2 * PATH_STEPS} (delta, theta) points", mesh["contact_size"],
                 mesh["layers"], 2, 0.0, path["result"]["dofs"], f"{path['wall']:.1f}", sum(its),
                 f"{np.median(its):g}", sum(path["result"]["factorizations"]),
                 f"{path['force'][-1]:.6e}", "", "", "", ""])
    header = ["case", "contact_size_m", "layers", "ranks", "friction", "dofs", "wall_time_s",
              "newton_total", "newton_per_step_median", "factorizations", "force_N",
              "force_error_rel", "reference_order", "speedup_vs_1_rank", "cost_vs_frictionless"]
    write_table(out, "fem3d", header, rows, plot)


def plot(path: Path, header, rows) -> None:
    """Force error against wall time (the reference level itself has none to show) and wall
    time against dofs."""
    col = {h: i for i, h in enumerate(header)}
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    for ranks, marker in ((1, "o"), (2, "s")):
        label = f"{ranks} rank{'s' if ranks > 1 else ''}"
        line = "-" if ranks == 1 else ""
        sel = [r for r in rows if r[col["ranks"]] == ranks and not r[col["friction"]]
               and r[col["force_error_rel"]] != ""]
        bx.loglog([r[col["dofs"]] for r in sel], [float(r[col["wall_time_s"]]) for r in sel],
                  marker, ls=line, label=label)
        shown = [r for r in sel if float(r[col["force_error_rel"]]) > 0]
        t = [float(r[col["wall_time_s"]]) for r in shown]
        errors = [float(r[col["force_error_rel"]]) for r in shown]
        ax.loglog(t, errors, marker, ls=line, label=label)
        for r, x, e in zip(shown, t, errors):
            ax.annotate(f"{r[col['dofs']]} dofs", (x, e), fontsize=7, xytext=(4, 4),
                        textcoords="offset points")
    friction = [r for r in rows if r[col["friction"]]]
    bx.loglog([r[col["dofs"]] for r in friction], [float(r[col["wall_time_s"]]) for r in friction],
              "^", label="mu = 0.2, 1 rank")
    ax.set_xlabel("wall time of `pinbore fem` (s)")
    ax.set_ylabel("force error at 10 um (vs reference)")
    bx.set_xlabel("dofs")
    bx.set_ylabel("wall time (s)")
    finish(fig, (ax, bx), path, "3D FE, steel pin in a 20 mm bore, c = 10 um, 5 load steps, "
                                "half model")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--large", action="store_true", help="add a ~200k-dof level on 2 ranks")
    args = parser.parse_args()
    main(args.out, args.large)
