"""Benchmark of the dynamic impact: run time against the error in the restitution e, over the
time step and the mesh.

Runs the shipped impact scene (scenes/impact/steel_c10um_v1.toml: steel pin, steel bore,
c = 10 um, 1 m/s) through `pinbore impact` with 25-400 steps over the estimated contact
(default mesh), with the energy control of the step (the default: fem.impact.solver) and with
fixed steps (adaptive_steps = false, 25-200), and on three meshes (coarse, default, refine
1; 100 steps, energy control). Writes OUT/impact.csv and OUT/impact.png:

- wall time of the whole command (start-up, meshing, assembly, time steps, output);
- dofs, steps, steps repeated by the energy control, Newton iterations per step;
- e, its error against the reference (the time-step series: the default mesh at 400 steps
  with energy control; the mesh series: refine 1), the energy book's residual (the energy
  the contact's integration lost) and the peak force.
"""

import argparse
import csv
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import tomli_w

from pinbore.core.figures import plt, save_png
from pinbore.fem.impact import file as impact_file

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "impact" / "steel_c10um_v1.toml"
STEPS = [25, 50, 100, 200, 400]   # energy control; fixed steps up to 200
MESHES = [("coarse", {"contact_size": 2e-4}), ("default", {}), ("refine 1", {"refine": 1})]


def run(scene: dict, workdir: Path, name: str) -> dict:
    """`pinbore impact` on `scene`: its wall time and impact.json."""
    path = workdir / f"{name}.toml"
    path.write_text(tomli_w.dumps(scene))
    out = workdir / name
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pinbore.cli", "impact", str(path), "--out", str(out)],
                   check=True, capture_output=True)
    return {"wall": time.perf_counter() - start,
            "summary": impact_file.read_summary(out / "impact.json")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    args = parser.parse_args()
    base = tomllib.loads(SCENE.read_text())
    series = {"fixed steps": [], "energy control": [], "mesh": []}
    with tempfile.TemporaryDirectory() as tmp:
        for kind, adaptive, counts in (("fixed steps", False, STEPS[:-1]),
                                       ("energy control", True, STEPS)):
            for n in counts:
                impact = base["impact"] | {"steps_per_contact": n, "adaptive_steps": adaptive}
                series[kind].append(("default", n, run(base | {"impact": impact}, Path(tmp),
                                                         f"steps{n}{'a' * adaptive}")))
        for name, mesh in MESHES:
            if name == "default":
                record = next(r for m, n, r in series["energy control"] if n == 100)
            else:
                record = run(base | {"mesh": mesh}, Path(tmp), name.replace(" ", ""))
            series["mesh"].append((name, 100, record))
    rows = []
    for kind, members in series.items():
        reference = (series["mesh"] if kind == "mesh" else series["energy control"])[-1][2]["summary"].restitution
        for mesh, n, record in members:
            s = record["summary"]
            rows.append({"series": kind, "mesh": mesh, "steps_per_contact": n,
                         "time_step_s": f"{s.time_step_s:.4g}", "dofs": s.dofs,
                         "steps": s.steps, "repeated": s.energy_rejections,
                         "smallest_step_s": f"{s.smallest_step_s:.3g}",
                         "newton_per_step": f"{s.newton_iterations / s.steps:.2f}",
                         "wall_time_s": f"{record['wall']:.2f}",
                         "restitution": f"{s.restitution:.6f}",
                         "restitution_error": f"{abs(s.restitution - reference):.2e}",
                         "energy_residual": f"{s.energy.residual_J_per_m / s.energy.impact_J_per_m:.2e}",
                         "max_energy_residual": f"{s.energy.max_relative_residual:.2e}",
                         "wave_energy": f"{s.energy.wave_J_per_m / s.energy.impact_J_per_m:.4f}",
                         "peak_force_N_per_m": f"{s.peak_force_N_per_m:.5g}",
                         "contact_duration_s": f"{s.contact_duration_s:.4g}"})
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "impact.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
    for kind, marker in (("fixed steps", "o--"), ("energy control", "o-"), ("mesh", "s-")):
        mine = [r for r in rows if r["series"] == kind and float(r["restitution_error"]) > 0]
        ax.loglog([float(r["wall_time_s"]) for r in mine],
                  [float(r["restitution_error"]) for r in mine], marker, label=kind)
        for r in mine:
            ax.annotate(f"{r['mesh']}, {r['steps_per_contact']}", (float(r["wall_time_s"]),
                        float(r["restitution_error"])), fontsize=7)
    ax.set_xlabel("wall time of pinbore impact (s)")
    ax.set_ylabel("|e - e_ref|")
    ax.set_title("restitution error against run time")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    for kind, marker in (("fixed steps", "o--"), ("energy control", "o-")):
        steps = [r for r in rows if r["series"] == kind]
        bx.loglog([float(r["wall_time_s"]) for r in steps],
                  [float(r["max_energy_residual"]) for r in steps], marker, label=kind)
        for r in steps:
            bx.annotate(str(r["steps_per_contact"]), (float(r["wall_time_s"]),
                        float(r["max_energy_residual"])), fontsize=7)
    bx.axhline(1e-3, color="k", lw=0.8, ls=":", label="energy_tolerance 1e-3")
    bx.set_xlabel("wall time of pinbore impact (s)")
    bx.set_ylabel("largest |energy residual| / impact energy")
    bx.set_title("the energy book (default mesh; labels: steps over the contact)")
    bx.legend()
    bx.grid(alpha=0.3, which="both")
    save_png(fig, args.out / "impact.png", layout=True)


if __name__ == "__main__":
    main()
