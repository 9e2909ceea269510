"""Benchmark of the impacts' Newton: the restitution study's points (studies/restitution.toml)
against the same points solved by the method before it (docs/theory/contact.md, the impacts'
Newton).

Each point runs `pinbore impact` on its scene (pinbore.study.point_scene). Writes
OUT/newton.csv and OUT/newton.png: per point, the Newton iterations a step (mean and median
over the accepted steps), the steps, the steps redone by the energy control, the cutbacks,
the LU factorisations of the Jacobian (redone and failed steps included), the time of the
time stepping and of the whole command, e and the energy book's largest residual; beside
them the same quantities of the earlier method (BEFORE: the Taylor predictor and an LU
factorisation at every Newton iteration, measured on the same machine) and e's change.

By default the four points of the issue's subset (the steel joint at c = 10 um and the
elasto-plastic 6061-O joint, 1 and 5 m/s); --all runs the study's twenty.
"""

import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from pinbore import study
from pinbore.core.figures import plt, save_png
from pinbore.fem.impact import file as impact_file

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem2d import write_table  # noqa: E402  (the benchmarks' one table writer)

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "studies" / "restitution.toml"
SUBSET = ["study_steel_c10um_v1000mm_s", "study_steel_c10um_v5000mm_s",
          "study_steel_al6061o_c500um_v1000mm_s", "study_steel_al6061o_c500um_v5000mm_s"]
# The earlier method on the same points and machine (the Taylor predictor q + h v + h^2 a / 2,
# an LU factorisation at every Newton iteration): Newton iterations (accepted steps), median a
# step, steps, redone, cutbacks, factorisations, solve time (s), e.
BEFORE = {
    "study_steel_c10um_v1000mm_s": (518, 4, 131, 30, 0, 626, 18.5, 0.5917535517),
    "study_steel_c10um_v5000mm_s": (654, 5, 140, 43, 0, 836, 30.1, 0.4876253252),
    "study_steel_al6061o_c500um_v1000mm_s": (885, 9, 93, 19, 0, 1172, 37.1, 0.7570788974),
    "study_steel_al6061o_c500um_v5000mm_s": (2243, 16, 145, 35, 17, 5680, 238.0, 0.4744435900),
}
HEADER = ["point", "newton_per_step", "newton_median", "steps", "redone", "cutbacks",
          "factorizations", "solve_s", "wall_s", "restitution", "max_energy_residual",
          "before_newton_per_step", "before_newton_median", "before_steps", "before_redone",
          "before_cutbacks", "before_factorizations", "before_solve_s", "before_restitution",
          "restitution_change"]


def run(name: str, workdir: Path) -> list:
    scene, out = workdir / f"{name}.toml", workdir / name
    study.point_scene(STUDY, name, scene)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "pinbore.cli", "impact", str(scene), "--out", str(out)],
                   check=True, capture_output=True)
    wall = time.perf_counter() - start
    s = impact_file.read_summary(out / impact_file.SUMMARY)
    history = impact_file.read_history(out / impact_file.HISTORY)
    its = np.asarray(history.newton_iterations)[1:]
    row = [name, f"{s.newton_iterations / s.steps:.2f}", f"{np.median(its):g}", s.steps,
           s.energy_rejections, s.cutbacks, s.factorizations, f"{s.wall_time_s['solve']:.1f}",
           f"{wall:.1f}", f"{s.restitution:.7f}", f"{s.energy.max_relative_residual:.2e}"]
    if name in BEFORE:
        newton, median, steps, redone, cuts, fact, solve, e = BEFORE[name]
        row += [f"{newton / steps:.2f}", median, steps, redone, cuts, fact, solve, f"{e:.7f}",
                f"{(s.restitution - e) / e:+.2e}"]
    else:
        row += [""] * 9
    return row


def plot(path: Path, header, rows) -> None:
    col = {h: i for i, h in enumerate(header)}
    known = [r for r in rows if r[col["before_solve_s"]] != ""]
    labels = [r[0].removeprefix("study_").replace("_", " ") for r in known]
    x = np.arange(len(known))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    for axis, after, before, title in (
            (ax, "newton_per_step", "before_newton_per_step", "Newton iterations a step"),
            (bx, "solve_s", "before_solve_s", "time stepping (s)")):
        axis.bar(x - 0.2, [float(r[col[before]]) for r in known], 0.4, label="before")
        axis.bar(x + 0.2, [float(r[col[after]]) for r in known], 0.4, label="after")
        axis.set_xticks(x, labels, rotation=20, fontsize=7)
        axis.set_title(title)
        axis.grid(alpha=0.3, axis="y")
        axis.legend()
    save_png(fig, path, layout=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--all", action="store_true", help="every point of the study")
    args = parser.parse_args()
    names = study.Plan(STUDY, study.load(STUDY)).point_names if args.all else SUBSET
    with tempfile.TemporaryDirectory() as tmp:
        rows = [run(name, Path(tmp)) for name in names]
    write_table(args.out, "newton", HEADER, rows, plot)


if __name__ == "__main__":
    main()
