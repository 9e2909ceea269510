"""Work-precision of the reduced model: CPU time against error for each integrator and
tolerance (adaptive DOPRI5 with onset location, Rosenbrock 2(3)) or step (fixed-step DOPRI5),
planar and spatial.

The Flores slider-crank with clearance (Lankarani-Nikravesh, e = 0.9, no friction), 4 crank
revolutions, one core, after compilation. The mechanism is chaotic after the first impacts,
so the error is measured on what is deterministic: the first impact's peak contact force and
its time (refined between the steps on the Hermite interpolant of the state,
reduced.mechanism.outputs.refined_peak), against a DOPRI5 run at rtol = 1e-11; statistics over
the run (mean and RMS contact force, impact count) are listed beside them. The same mechanism
as a spatial scene (scenes/reduced/spatial_slider_crank_flores) against its own DOPRI5 run at
rtol = 1e-11. Every scene goes through the one mechanism model whatever its kind
(reduced.mechanism.kinds, .model, .run, .outputs); the rows' `model` is the scene's kind.
Times are CPU times of the integration (time.process_time, the median of three runs after
compilation; the machine is shared, so wall time would measure the neighbours). Writes
OUT/reduced.csv and OUT/reduced.png.
"""

import argparse
import statistics
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pinbore.core.figures import plt, save_png
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.model import build, fixed_step
from pinbore.reduced.mechanism.outputs import per_step, refined_peak
from pinbore.reduced.mechanism.run import simulate

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
RUNS = ([{"method": "dopri5", "rtol": r, "atol": r * 1e-3} for r in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)]
        + [{"method": "rosenbrock23", "rtol": r, "atol": r * 1e-3} for r in (1e-3, 1e-4, 1e-5)]
        + [{"method": "dopri5_fixed", "fixed_step": h} for h in (2e-6, 1e-6, 5e-7, 2.5e-7)]
        + [{"method": "dopri5_fixed"}])   # its default step, 1/300 of the contact period
SPATIAL_SCENE = ROOT / "scenes" / "reduced" / "spatial_slider_crank_flores.toml"
SPATIAL_RUNS = ([{"method": "dopri5", "rtol": r, "atol": r * 1e-3} for r in (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6)]
                + [{"method": "rosenbrock23", "rtol": 1e-4, "atol": 1e-7}])


JOINT = "rod_slider"   # the clearance joint whose first impact is measured
# per scene: its runs, and how its curves are drawn (marker, label prefix)
BENCHES = [(SCENE, RUNS, "o-", ""), (SPATIAL_SCENE, SPATIAL_RUNS, "s--", "spatial model: ")]
REFERENCE = {"method": "dopri5", "rtol": 1e-11, "atol": 1e-14}


def scene_with(path: Path, integrator: dict):
    """The scene file at `path` (of any kind, validated through the registry) with its
    integrator table replaced by `integrator`."""
    scene = kinds.load(path)
    return kinds.validate(scene.model_dump() | {"integrator": integrator}, str(path))


def measure(path: Path, integrator: dict, repeats=3) -> dict:
    model = build(scene_with(path, integrator), str(path), path.parent)
    simulate(model)   # a first run: imports and caches warm
    runs, cpu = [], []
    for _ in range(repeats):
        start = time.process_time()
        runs.append(simulate(model))
        cpu.append(time.process_time() - start)
    run = runs[-1]
    times, counters = run.times, run.counters
    cols, energy, drift = per_step(model, run)
    total = energy["kinetic"] + energy["potential"] + energy["elastic"] + energy["dissipated"] \
        - energy["work_in"]
    residual = float(np.max(np.abs(total - total[0])) / np.max(energy["kinetic"]))
    force = cols[f"{JOINT}_normal_force_N"]
    first = np.flatnonzero(force > 0)
    end = first[0] + np.argmax(force[first[0]:] == 0)
    k = int(first[0] + np.argmax(force[first[0]:end]))
    peak_force, peak_time = refined_peak(model, [c.name for c in model.joints].index(JOINT), run, k)
    dt = np.diff(times)
    mean = float(np.sum(force[1:] * dt) / times[-1])
    rms = float(np.sqrt(np.sum(force[1:] ** 2 * dt) / times[-1]))
    return {"model": model.kind.name, "method": integrator["method"], "setting": integrator["rtol"] if "rtol" in integrator else fixed_step(model), "wall": statistics.median(r.seconds for r in runs), "cpu": statistics.median(cpu), "peak": peak_force,
            "t_peak": peak_time, "mean": mean, "rms": rms, "impacts": int(counters[3]),
            "steps": int(counters[0]), "rhs": int(counters[2]), "status": run.status,
            "drift": float(drift.max()), "energy": residual}


def main(out: Path) -> None:
    # per scene: its rows, its reference, how it is drawn
    groups = []
    for path, runs, marker, prefix in BENCHES:
        reference = measure(path, REFERENCE, repeats=1)
        rows = [measure(path, r) for r in tqdm(runs, desc=f"work-precision, {reference['model']}", unit="run")]
        groups.append((rows, reference, marker, prefix))
    out.mkdir(parents=True, exist_ok=True)
    header = ["model", "method", "rtol_or_step_s", "wall_time_s", "cpu_time_s", "steps", "rhs_evaluations",
              "first_peak_N", "first_peak_error_rel", "first_peak_time_error_s", "mean_force_N",
              "rms_force_N", "impacts", "constraint_drift_m", "energy_residual_rel"]
    lines = [",".join(header)]
    for rows, ref, _, _ in groups:
        for r in rows + [ref]:
            lines.append(",".join(str(v) for v in [
                r["model"], r["method"], r["setting"], f"{r['wall']:.4f}", f"{r['cpu']:.4f}", r["steps"], r["rhs"],
                f"{r['peak']:.6g}", f"{abs(r['peak'] / ref['peak'] - 1):.2e}",
                f"{abs(r['t_peak'] - ref['t_peak']):.2e}", f"{r['mean']:.5g}", f"{r['rms']:.5g}",
                r["impacts"], f"{r['drift']:.1e}", f"{r['energy']:.1e}"]))
    (out / "reduced.csv").write_text("\n".join(lines) + "\n")
    fig, ax = plt.subplots(figsize=(7, 4.5))
    labels = {"dopri5": "DOPRI5, adaptive, onsets located", "rosenbrock23": "Rosenbrock 2(3), adaptive",
              "dopri5_fixed": "DOPRI5, fixed step"}
    series = [(rows, ref, method, marker, prefix + label) for rows, ref, marker, prefix in groups
              for method, label in labels.items() if any(r["method"] == method for r in rows)]
    for group, ref, method, marker, label in series:
        mine = [r for r in group if r["method"] == method]
        error = [max(abs(r["peak"] / ref["peak"] - 1), 1e-12) for r in mine]
        ax.loglog([r["cpu"] for r in mine], error, marker, label=label)
        for r, e in zip(mine, error):
            ax.annotate(f"{'h' if method == 'dopri5_fixed' else 'rtol'} {r['setting']:g}", (r["cpu"], e),
                        fontsize=6, xytext=(4, 4), textcoords="offset points")
    ax.axhline(0.01, color="0.5", ls=":", label="1 % (target)")
    ax.axvline(0.03, color="0.5", ls="--", label="0.03 s (target, planar)")
    ax.axvline(0.06, color="0.7", ls="--", label="0.06 s (target, spatial)")
    ax.set_xlabel("CPU time, 4 revolutions, one core (s)")
    ax.set_ylabel("first-impact peak force error")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    save_png(fig, out / "reduced.png", layout=True)
    print((out / "reduced.csv").read_text())


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
