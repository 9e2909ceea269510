"""Benchmark of the 2D FE contact: run time against error, both methods, several meshes.

Runs the default scene (scenes/fem/steel_c10um.toml, 10 load steps) through `pinbore fem`
at several mesh levels, with the penalty method and the augmented Lagrangian, and once on
2 MPI ranks. Writes OUT/fem2d.csv and OUT/fem2d.png:

- wall time of the whole command (start-up, meshing, assembly, solve, output);
- dofs, Newton iterations per load step (median and largest);
- force error at the largest approach against the mesh-converged force (Richardson
  extrapolation of the three finest levels, with their observed order), and against the
  Persson force at the FE half-angle (this one carries the model's hub effect too);
- half-angle error: the largest |FE - Persson| over the load steps, Persson evaluated at
  the FE force (similar materials; the model's 0.2 R hub stiffens the pin, about 1 deg).
"""

import argparse
import csv
import json
import math
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import matplotlib.ticker
import numpy as np
import tomli_w

from pinbore.core.figures import plt, save_png
from pinbore.fem import curve as fe_curve
from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import persson_half_angles, persson_load

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "fem" / "steel_c10um.toml"
LEVELS = [("coarse", {"contact_size": 1.75e-4, "grading": 0.5}), ("default", {}),
          ("refine 1", {"refine": 1}), ("refine 2", {"refine": 2})]
METHODS = ["penalty", "augmented-lagrangian"]


def run(scene: dict, workdir: Path, name: str, ranks: int = 1) -> dict:
    """`pinbore fem` on `scene` (on `ranks` MPI ranks): its wall time, result.json, and the
    force (2D: per unit length, N/m; 3D: of the whole pin, N) and half-angle of every step."""
    path = workdir / f"{name}.toml"
    path.write_text(tomli_w.dumps(scene))
    out = workdir / name
    command = [sys.executable, "-m", "pinbore.cli", "fem", str(path), "--out", str(out)]
    if ranks > 1:
        command = [str(Path(sys.executable).parent / "mpiexec"), "-n", str(ranks)] + command
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    wall = time.perf_counter() - start
    curve = fe_curve.read(out / "curve.csv")
    result = json.loads((out / "result.json").read_text())
    return {"wall": wall, "result": result, "force": curve.force, "angle": curve.half_angle}


def persson_errors(scene: dict, force, angle) -> tuple[float, float]:
    """Largest |half-angle - Persson(force)| (deg); |force / Persson(half-angle) - 1| at the
    largest approach."""
    joint = FemScene.model_validate(scene).joint
    closed = np.degrees(persson_half_angles(force, joint))
    closed_force = joint.e_star * joint.clearance * persson_load(math.tan(math.radians(angle[-1]) / 2))
    return float(np.max(np.abs(angle - closed))), abs(force[-1] / closed_force - 1)


def main(out: Path) -> None:
    base = tomllib.loads(SCENE.read_text())
    base["output"] = {"picture": False, "fields": False}
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        cases = [(level, mesh, method, 1) for level, mesh in LEVELS for method in METHODS]
        cases.append(("default", {}, "augmented-lagrangian", 2))
        for i, (level, mesh, method, ranks) in enumerate(cases):
            scene = json.loads(json.dumps(base))
            scene["mesh"] = mesh
            scene["contact"]["method"] = method
            print(f"[{i + 1}/{len(cases)}] {level}, {method}, {ranks} rank(s)", flush=True)
            records.append((level, method, ranks, scene, run(scene, Path(tmp), f"case{i}", ranks)))
    # mesh-converged force from the three finest levels (same method)
    rows = []
    for method in METHODS:
        finest = [r[4]["force"][-1] for r in records if r[1] == method and r[2] == 1][-3:]
        order = math.log2(abs(finest[1] - finest[0]) / abs(finest[2] - finest[1]))
        limit = finest[2] + (finest[2] - finest[1]) / (2**order - 1)
        for level, m, ranks, scene, r in records:
            if m != method:
                continue
            its = r["result"]["newton_iterations"]
            angle_error, force_error = persson_errors(scene, r["force"], r["angle"])
            rows.append([level, method, ranks, r["result"]["dofs"],
                         f"{r['result']['mesh']['contact_size_m']:.3g}", f"{r['wall']:.2f}",
                         f"{np.median(its):g}", max(its), f"{r['force'][-1]:.6e}",
                         f"{abs(r['force'][-1] / limit - 1):.2e}", f"{force_error:.2e}",
                         f"{angle_error:.3f}", f"{order:.2f}"])
    header = ["mesh", "method", "ranks", "dofs", "contact_size_m", "wall_time_s",
              "newton_per_step_median", "newton_per_step_max", "force_N_per_m",
              "force_error_rel", "force_error_vs_persson", "half_angle_error_deg",
              "observed_order"]
    write_table(out, "fem2d", header, rows, plot)


def write_table(out: Path, name: str, header, rows, plot) -> None:
    """OUT/name.csv and the plot(OUT/name.png, header, rows) of a benchmark; print the table."""
    out.mkdir(parents=True, exist_ok=True)
    with open(out / f"{name}.csv", "w", newline="") as f:
        csv.writer(f).writerows([header] + rows)
    plot(out / f"{name}.png", header, rows)
    print((out / f"{name}.csv").read_text())


def plot(path: Path, header, rows) -> None:
    col = {h: i for i, h in enumerate(header)}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for method, marker in zip(METHODS, "os"):
        for ranks, fill in ((1, "full"), (2, "none")):
            sel = [r for r in rows if r[col["method"]] == method and r[col["ranks"]] == ranks]
            if not sel:
                continue
            t = [float(r[col["wall_time_s"]]) for r in sel]
            label = f"{method}, {ranks} rank{'s' if ranks > 1 else ''}"
            axes[0].loglog(t, [float(r[col["force_error_rel"]]) for r in sel], marker=marker,
                           fillstyle=fill, label=label)
            axes[1].semilogx(t, [float(r[col["half_angle_error_deg"]]) for r in sel],
                             marker=marker, fillstyle=fill, label=label)
            if method != METHODS[0] or ranks != 1:
                continue
            for r, x in zip(sel, t):
                axes[0].annotate(f"{r[col['dofs']]} dofs", (x, float(r[col["force_error_rel"]])),
                                 fontsize=7, xytext=(4, 4), textcoords="offset points")
    axes[0].set_ylabel("force error at largest approach (vs Richardson limit)")
    axes[1].set_ylabel("largest |half-angle - Persson| (deg)")
    for ax in axes:
        ax.set_xlabel("wall time of `pinbore fem` (s)")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    finish(fig, axes, path, "2D FE, scene steel_c10um (c = 10 um, 10 load steps)")


def finish(fig, axes, path: Path, title: str) -> None:
    """Grids, legends and a title; write the PNG without time stamps."""
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle(title)
    save_png(fig, path, layout=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
