"""Benchmark of the elasto-plastic FE: a 2D loading-unloading curve against the elastic one.

The default scene (scenes/fem/steel_c10um.toml, 10 load steps to 10 um) with `unload = true`
(10 unloading steps and the search for zero force), frictionless, at three mesh levels;
elastic, and with a plastic bore (Y = 40 MPa, linear hardening H = 2 GPa: the plastic zone
under the contact grows to a few millimetres, the residual approach is about 0.3 of
max_approach). Each case runs `pinbore fem` twice (the first run also compiles the
quadrature forms into FFCx's cache); the second is timed. Writes
OUT/plastic.csv and OUT/plastic.png:

- wall time of the whole command and of its load stepping (result.json), Newton iterations;
- the cost ratio plastic / elastic on the same mesh (the goal: at most 2);
- the plastic work of the loop, the elastic energy it leaves locked, the residual approach.
"""

import argparse
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
from pinbore.fem import curve as fe_curve

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem2d import write_table  # noqa: E402  (the benchmarks' one table writer)

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "fem" / "steel_c10um.toml"
LEVELS = [("coarse", {"contact_size": 1.75e-4, "grading": 0.5}), ("default", {}),
          ("refine 1", {"refine": 1})]
BORE_YIELD = {"yield_stress": 40e6, "hardening_modulus": 2e9}


def run(scene: dict, workdir: Path, name: str):
    """`pinbore fem` on `scene`, twice; the wall time of the second, result.json, curve."""
    path = workdir / f"{name}.toml"
    path.write_text(tomli_w.dumps(scene))
    for attempt in range(2):
        out = workdir / f"{name}_{attempt}"
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pinbore.cli", "fem", str(path), "--out", str(out)],
                       check=True, capture_output=True)
        wall = time.perf_counter() - start
    return wall, json.loads((out / "result.json").read_text()), fe_curve.read(out / "curve.csv")


def main(out: Path) -> None:
    base = tomllib.loads(SCENE.read_text())
    base["output"] = {"picture": False, "fields": False}
    base["load"]["unload"] = True
    rows, curves = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for level, mesh in LEVELS:
            timings = {}
            for material in ("elastic", "plastic"):
                scene = json.loads(json.dumps(base))
                scene["mesh"] = mesh
                if material == "plastic":
                    scene["materials"]["bore"].update(BORE_YIELD)
                print(f"{level}, {material}", flush=True)
                wall, result, curve = run(scene, Path(tmp), f"{level}_{material}".replace(" ", ""))
                solve = result["wall_time_s"]["solve"]
                timings[material] = (wall, solve)
                curves[(level, material)] = curve
                ends = np.flatnonzero(np.isfinite(curve.residual_approach))
                its = result["newton_iterations"]
                rows.append([level, material, result["dofs"], result["status"], curve.points,
                             f"{wall:.2f}", f"{solve:.2f}", sum(its), f"{np.median(its):g}",
                             result["cutbacks"], f"{curve.force.max():.6e}",
                             f"{curve.plastic_work.sum():.6e}",
                             f"{curve.residual_approach[ends[-1]]:.4e}" if ends.size else "nan",
                             f"{wall / timings['elastic'][0]:.2f}",
                             f"{solve / timings['elastic'][1]:.2f}"])
    header = ["mesh", "material", "dofs", "status", "steps", "wall_time_s", "solve_time_s",
              "newton_iterations", "newton_per_step_median", "cutbacks", "peak_force_N_per_m",
              "plastic_work_J_per_m", "residual_approach_m", "wall_ratio_to_elastic",
              "solve_ratio_to_elastic"]
    write_table(out, "plastic", header, rows, lambda path, h, r: plot(path, h, r, curves))


def plot(path: Path, header, rows, curves) -> None:
    col = {h: i for i, h in enumerate(header)}
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    for (level, material), curve in curves.items():
        if level != "default":
            continue
        ax.plot(curve.approach * 1e6, curve.force / 1e3, "o-" if material == "plastic" else "s--",
                ms=3, label=f"{material} bore" + (" (Y = 40 MPa, H = 2 GPa)" if material == "plastic" else ""))
    ax.set_xlabel("approach beyond first touch (um)")
    ax.set_ylabel("force per length (kN/m)")
    ax.set_title("load and unload to zero force, default mesh")
    levels = [lv for lv, _ in LEVELS]
    for material, marker in (("elastic", "s"), ("plastic", "o")):
        sel = [r for r in rows if r[col["material"]] == material]
        bx.plot([int(r[col["dofs"]]) for r in sel], [float(r[col["solve_time_s"]]) for r in sel],
                marker=marker, label=f"{material}: load stepping")
        bx.plot([int(r[col["dofs"]]) for r in sel], [float(r[col["wall_time_s"]]) for r in sel],
                marker=marker, ls=":", label=f"{material}: whole command")
    for r in rows:
        if r[col["material"]] == "plastic":
            bx.annotate(f"x{r[col['solve_ratio_to_elastic']]}", (int(r[col["dofs"]]),
                        float(r[col["solve_time_s"]])), fontsize=8, xytext=(4, -10),
                        textcoords="offset points")
    bx.set_xscale("log")
    bx.set_xlabel(f"dofs ({', '.join(levels)})")
    bx.set_ylabel("wall time (s)")
    bx.set_title("cost of the load-unload curve (annotated: plastic / elastic)")
    for a in (ax, bx):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=8)
    fig.suptitle("2D elasto-plastic FE, scene steel_c10um with unload = true")
    save_png(fig, path, layout=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
