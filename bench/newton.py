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

By default four points (the steel joint at c = 10 um and the elasto-plastic 6061-O joint, 1
and 5 m/s); --all runs the study's twenty.
"""

import argparse
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
# The earlier method on the same points and machine, loaded alike (the Taylor predictor
# q + h v + h^2 a / 2, an LU factorisation at every Newton iteration): Newton iterations
# (accepted steps), median a step, steps, redone, cutbacks, factorisations, solve time (s), e.
BEFORE = {
    "study_steel_c10um_v0100mm_s": (339, 4, 97, 18, 0, 401, 9.6, 0.7669127635),
    "study_steel_c10um_v0300mm_s": (348, 3, 109, 20, 0, 404, 11.4, 0.6994668744),
    "study_steel_c10um_v1000mm_s": (518, 4, 131, 30, 0, 626, 18.5, 0.5917535517),
    "study_steel_c10um_v3000mm_s": (623, 4, 150, 48, 0, 816, 30.0, 0.5088311102),
    "study_steel_c10um_v5000mm_s": (654, 5, 140, 43, 0, 836, 30.1, 0.4876253252),
    "study_steel_c100um_v0100mm_s": (190, 3, 78, 11, 0, 213, 4.2, 0.8445898401),
    "study_steel_c100um_v0300mm_s": (267, 3, 83, 10, 0, 300, 6.1, 0.8122580368),
    "study_steel_c100um_v1000mm_s": (348, 4, 97, 22, 0, 424, 9.8, 0.7661490414),
    "study_steel_c100um_v3000mm_s": (414, 4, 108, 20, 0, 479, 13.9, 0.6985132282),
    "study_steel_c100um_v5000mm_s": (486, 5, 113, 15, 0, 540, 17.7, 0.6547309510),
    "study_steel_al_c10um_v0100mm_s": (334, 3, 101, 9, 0, 359, 9.7, 0.7354684142),
    "study_steel_al_c10um_v0300mm_s": (414, 4, 113, 11, 0, 449, 13.9, 0.6731632657),
    "study_steel_al_c10um_v1000mm_s": (581, 5, 137, 23, 0, 667, 22.2, 0.5909464147),
    "study_steel_al_c10um_v3000mm_s": (827, 6, 154, 20, 0, 907, 41.9, 0.5291799420),
    "study_steel_al_c10um_v5000mm_s": (857, 6, 153, 25, 0, 972, 37.1, 0.5131424048),
    "study_steel_al6061o_c500um_v0100mm_s": (549, 7.5, 66, 8, 0, 678, 22.6, 0.8466976258),
    "study_steel_al6061o_c500um_v0300mm_s": (735, 9, 74, 8, 0, 1009, 33.4, 0.8270507931),
    "study_steel_al6061o_c500um_v1000mm_s": (885, 9, 93, 19, 0, 1172, 37.1, 0.7570788974),
    "study_steel_al6061o_c500um_v3000mm_s": (1441, 13, 111, 23, 5, 2693, 134.4, 0.5754091564),
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
    newton, median, steps, redone, cuts, fact, solve, e = BEFORE[name]
    return row + [f"{newton / steps:.2f}", median, steps, redone, cuts, fact, solve, f"{e:.7f}",
                  f"{(s.restitution - e) / e:+.2e}"]


def plot(path: Path, header, rows) -> None:
    col = {h: i for i, h in enumerate(header)}
    labels = [r[0].removeprefix("study_").replace("_", " ") for r in rows]
    x = np.arange(len(rows))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.8))
    for axis, after, before, title in (
            (ax, "newton_per_step", "before_newton_per_step", "Newton iterations a step"),
            (bx, "solve_s", "before_solve_s", "time stepping (s)")):
        was, now = ([float(r[col[c]]) for r in rows] for c in (before, after))
        axis.bar(x - 0.2, was, 0.4, label="before")
        axis.bar(x + 0.2, now, 0.4, label="after")
        axis.set_xticks(x, labels, rotation=60, fontsize=6)
        axis.set_title(f"{title}: {sum(was):.4g} before, {sum(now):.4g} after"
                       if after == "solve_s" else title)
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
